"""Pixel sizes fitted to the body's size in each view (the tracker's ``auto_scale``).

The tracker's settings counted in pixels (pyramid levels, the finest level's sampling, the
silhouette's reach, the backdrop's margin) were measured on footage where the body stands
about ``REFERENCE_BODY_PIXELS`` tall. A view where it stands 2^k times that (k, its octaves,
rounded) gets k finer pyramid levels on top of the settings' ``levels``, samples them as many
full-resolution pixels apart as its original finest level, and scales the silhouette's reach
and the backdrop's margin by 2^k. A body smaller than that (k < 0) loses as many of the
settings' coarsest levels (one is always kept), is sampled at every pixel and gets the
reach and margin scaled down alike, but only where several views see it: one view has no
other to re-find a limb that moved far, and its long reach and coarse level are what do
(measured in ``docs/RESEARCH.md``). The tracker's level L (0: the largest view's finest)
reads view c on its level L - (K - k_c), K being the largest view's octaves (its full
resolution where that is below 0), so that the body is about as large in every view on
every level.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .pose import BodyPose
from .skeleton import Skeleton

# the body's height in the footage (pixels) that the pixel-sized settings are meant for: the
# benchmark's 480x360 views, where they were measured, show it 205 pixels tall
REFERENCE_BODY_PIXELS = 200.0


def view_octaves(skeleton: Skeleton, pose: BodyPose) -> list[int]:
    """Per view, how many times the body at ``pose`` is twice as tall there as
    ``REFERENCE_BODY_PIXELS`` (its rest pose's largest extent, rounded in octaves; negative
    for a smaller body)."""
    return [int(np.round(np.log2(skeleton.height() * v.scale_at(pose.root_position)
                                 / REFERENCE_BODY_PIXELS))) for v in pose.views]


@dataclass(frozen=True)
class Scales:
    """The pixel sizes of one body size per view: ``octaves`` per view, on top of the
    settings' ``levels``, ``pixel_step`` and ``silhouette_cap``."""

    octaves: tuple[int, ...]
    levels: int
    pixel_step: int
    silhouette_cap: float

    @classmethod
    def unscaled(cls, n_views: int, settings) -> Scales:
        """The tracker's ``settings`` as they are, in every view (no octaves)."""
        return cls((0,) * n_views, settings.levels, settings.pixel_step,
                   settings.silhouette_cap)

    @classmethod
    def of(cls, skeleton: Skeleton, pose: BodyPose, settings) -> Scales:
        """The scales for the body at ``pose`` (every view's octaves 0 unless the tracker's
        ``settings`` ask for ``auto_scale``): a smaller body's octaves only with several
        views, and never so far below 0 that no pyramid level is left."""
        unscaled = cls.unscaled(len(pose.views), settings)
        if not settings.auto_scale:
            return unscaled
        floor = 1 - settings.levels if len(pose.views) > 1 else 0
        return replace(unscaled, octaves=tuple(max(k, floor)
                                               for k in view_octaves(skeleton, pose)))

    def pyramid_levels(self) -> list[int]:
        """Per view, the levels of its pyramid."""
        return [self.levels + k for k in self.octaves]

    def n_levels(self) -> int:
        """The tracker's levels: the largest view's pyramid levels."""
        return self.levels + max(self.octaves)

    def view_level(self, view: int, level: int) -> int:
        """The pyramid level of ``view`` that tracker level ``level`` reads."""
        return max(level - (max(self.octaves) - self.octaves[view]), 0)

    def view_levels(self, level: int) -> list[int]:
        """Every view's pyramid level that tracker level ``level`` reads."""
        return [self.view_level(c, level) for c in range(len(self.octaves))]

    def search_level(self) -> int:
        """The tracker level the limbs are searched on, after the coarser ones placed the
        body."""
        return min(1 + max(self.octaves), self.n_levels() - 1)

    def grid(self, view: int, lv: int) -> int:
        """Level pixels between samples of ``view``'s point sets and label maps on its level
        ``lv``: every ``pixel_step``-th on the finest of the settings' levels, and as many
        full-resolution pixels apart on the finer levels a large body adds; every pixel of
        a small body's (as on the settings' coarser levels)."""
        k = self.octaves[view]
        return self.pixel_step * 2 ** (k - lv) if lv <= k else 1

    def cap(self, view: int) -> float:
        """``silhouette_cap`` in full-resolution pixels of ``view``."""
        return self.silhouette_cap * 2.0 ** self.octaves[view]

    def magnification(self, view: int) -> float:
        """How many times the body in ``view`` is as large as the settings are meant for
        (2^octaves): the backdrop's margin is scaled by it and, for a larger body, the
        body's mask drawn this many pixels apart."""
        return 2.0 ** self.octaves[view]
