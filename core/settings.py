"""The tracker's settings: every knob with its default and what it does, settable from a
job's ``settings`` and shown as the add-on's Track settings (their tooltips are the fields'
``doc``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from .errors import InputError
from .scales import REFERENCE_BODY_PIXELS


def _knob(default, doc: str):
    return field(default=default, metadata={"doc": doc})


@dataclass
class TrackerSettings:
    """Tracker knobs with their defaults; every field can be set from a job's ``settings``,
    and each field's ``metadata["doc"]`` says what it does (the add-on's tooltips)."""

    levels: int = _knob(3, "Pyramid levels, coarse to fine (1: full resolution only)")
    highpass: float = _knob(4.0, "Shading removal: subtract the local mean over this many "
                            "pixels of each level (0: off)")
    iterations: int = _knob(6, "Gauss-Newton iterations per pyramid level, at most (half as "
                            "many where each view has its own scaled camera: independent mode)")
    pixel_step: int = _knob(2, "Use every n-th pixel across and down on the finest level")
    auto_scale: bool = _knob(True, "Fit the settings counted in pixels to the body's size in "
                             "each view: where it stands over about 280 pixels tall, that "
                             "view is tracked as if halved once per doubling over "
                             f"{REFERENCE_BODY_PIXELS:g}, with its finer pixels sampled "
                             "sparsely on added pyramid levels (faster, and steadier); with "
                             "several views, where it stands under about 140, with a coarse "
                             "level fewer, every pixel sampled and a shorter silhouette reach")
    key_weight: float = _knob(0.5, "Weight of the key frame's pixels against the previous "
                              "frame's: holds the track against drift")
    colour: bool = _knob(True, "Match colour footage in its hue as well as its brightness: "
                         "each body pixel is held to two chroma channels beside its grey "
                         "value, each channel with its own noise level, so that cloth "
                         "whose colours differ more than their brightness is followed. "
                         "Costs about 1.3 times the time and, on HD footage, half again "
                         "the memory; grey footage is not affected")
    damping: float = _knob(1e-2, "Initial Levenberg-Marquardt damping")
    max_step: float = _knob(15.0, "Degrees any joint may turn in one iteration")
    prior: float = _knob(0.0, "Pull toward the predicted pose, relative to what the pixels "
                         "say about each unknown")
    outlier_density: float = _knob(0.1, "Support maps: how likely a pixel is not to follow "
                                   "its blob (background, occluders, highlights)")
    noise_floor: float = _knob(0.01, "Smallest brightness noise assumed (0 to 1)")
    registration_noise: float = _knob(0.6, "How far a body pixel may lie from where the "
                                      "blobs put it, in pixels of each pyramid level (the "
                                      "blobs are not the body's shape; samples fall between "
                                      "pixels): each pixel's brightness noise grows by its "
                                      "gradient times this, so a steep edge, which a small "
                                      "misplacement changes most, counts less than flat "
                                      "texture; only on the previous frame's pixels (the "
                                      "key frame's hold the track against drift) of segments "
                                      "two or more views see (one view's edges are what "
                                      "tells its limbs apart; 0: every pixel its set's "
                                      "noise)")
    rim_width: float = _knob(0.3, "Blob outline band whose pixels count less, as a share of "
                             "the blob's radius")
    prediction_gain: float = _knob(1.0, "Constant-velocity prediction of the next frame "
                                   "(0: start from the last pose)")
    converge_pixels: float = _knob(0.2, "Stop iterating a level when no blob moves more "
                                   "pixels than this")
    min_blob_pixels: float = _knob(1.5, "Solve a joint on levels where its blob is at least "
                                   "this many pixels thick")
    divergence_ratio: float = _knob(3.0, "Flag a frame whose residual exceeds the median so "
                                    "far by this factor")
    divergence_jump: float = _knob(2.0, "Flag such a frame only if its residual also exceeds "
                                   "the lower of the two frames' before it by this factor: a "
                                   "lost fit breaks within a frame or two, while a residual "
                                   "that climbs over more is the body turning new sides to "
                                   "the cameras, which the limbs' checks report (0: the "
                                   "median alone)")
    min_inside: float = _knob(0.5, "Flag a frame when less of the body than this stays "
                              "inside a view's image")
    stop_on_divergence: bool = _knob(True, "Stop at the first flagged frame")
    silhouette: float = _knob(0.1, "Weight of the body's silhouette against the "
                              "backdrop (0: off): pulls limbs onto the outline from farther "
                              "than brightness reaches. Needs cameras that stand still "
                              "or only turn about their centres")
    silhouette_cap: float = _knob(24.0, "Farthest a silhouette mismatch pulls, in pixels of "
                                  "the full image")
    side_on: bool = _knob(True, "Where every view looks along one line (one view): track "
                          "every joint that could turn toward or away from the camera as a "
                          "hinge about the line of sight (a moving camera's mean over the "
                          "frames; a limited hinge keeping the image angles its range "
                          "reaches), as the paper does with one camera, and turn the body "
                          "itself only about that line: the limbs follow the footage in the "
                          "image, and what the footage does not show in depth is held, not "
                          "guessed (off: those turns are read from foreshortening alone). "
                          "Views that look different ways are not affected")
    limb_search: float = _knob(0.1, "Before refining a frame, turn each limb over a grid of "
                               "angles against the silhouette and keep the best turn when it "
                               "beats the prediction by this share of the limb's outline, "
                               "and by that again per 45 degrees of turn squared, and every "
                               "view whose pixels see the limb bears the turn out, or two or "
                               "more views' backdrops show the limb cannot be where it is and "
                               "can be where it turned, or three or more views see its outline "
                               "and each scores the turn better by this share, or two or more "
                               "see it off the body and on the body turned (0: off). "
                               "Catches limbs faster than a blob's width a frame")
    release_lost_limbs: bool = _knob(True, "A limb in doubt on the frame before leaves out "
                                     "its pixels of that frame that the view's still "
                                     "backdrop shows were backdrop: a limb lost onto a "
                                     "textured backdrop is otherwise held there by the "
                                     "backdrop's own pixels, which do not move")

    def __post_init__(self):
        for name in ("levels", "iterations", "pixel_step"):
            if int(getattr(self, name)) < 1:
                raise InputError(f"settings.{name} must be a whole number >= 1")
