"""Where doubt begins, marked on the timeline: one marker per tracked frame where a limb's
flag begins (``core.tracker.doubts_begun``), named for those limbs, so that the user can
step through them with the timeline's marker jumps. Markers are told from the user's own by
their name's prefix."""

from __future__ import annotations

from collections.abc import Iterable

from ..core.confidence import UNSEEN
from ..core.side_on import TURNED

PREFIX = "check: "
MAX_NAME = 63  # characters Blender keeps of a marker's name


def marker_name(flagged: dict[str, str]) -> str:
    """'check: LeftElbow, LeftKnee unseen, body turned', cut to what a marker's name
    holds."""
    text = PREFIX + ", ".join(f"{bone}{f' {why}' * (why in (UNSEEN, TURNED))}"
                              for bone, why in flagged.items())
    return text if len(text) <= MAX_NAME else text[:MAX_NAME - 3] + "..."


def unmark(scene, frames: Iterable[int] | None = None) -> int:
    """Remove the check markers (on ``frames``, or all); returns how many went."""
    frames = None if frames is None else set(frames)
    ours = [m for m in scene.timeline_markers if m.name.startswith(PREFIX)
            and (frames is None or m.frame in frames)]
    for m in ours:
        scene.timeline_markers.remove(m)
    return len(ours)


def mark(scene, frame: int, flagged: dict[str, str]) -> None:
    """Mark ``frame`` as where the ``flagged`` limbs' doubt begins (bone -> flag), replacing
    an earlier run's check marker there; no marker when nothing is flagged."""
    unmark(scene, [frame])
    if flagged:
        scene.timeline_markers.new(marker_name(flagged), frame=frame)
