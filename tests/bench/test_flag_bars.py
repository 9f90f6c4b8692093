"""Flags read again from a report: the tracker's own flags given back at the bars in use,
each limb's flag carried from frame to frame as the tracker carries it, and the suite's
reports of the default settings alone."""

import copy
import sys
from pathlib import Path

import numpy as np

from core.confidence import CLEAR, DOUBT, UNSEEN, UNSURE_FLAG, Limbs
from core.pose import CALIBRATED, BodyPose
from core.raycast import BlobStack
from core.settings import TrackerSettings
from core.skeleton import human_template
from core.tracker import Tracker, track
from support.synthetic import render, side_view

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from flag_bars import reflagged  # noqa: E402


def _report(frames) -> dict:
    """The report's frames (``core.run.report``'s ``frames``) of tracked results, its
    confidences unrounded."""
    return {"frames": [{"limbs": {n: {"confidence": c.own_confidence,
                                      "views": list(c.flag_views),
                                      "flag": c.flag, "unexplained": c.unexplained}
                                  for n, c in fr.limbs.items()}}
                       for fr in frames]}


def test_read_again_at_the_bars_in_use_a_one_view_report_gives_the_trackers_flags_back():
    """Side-on in one view, the near forearm gone on one frame: every limb's flag read again
    from the report at the tracker's bars (and the unexplained foreground's weight in use)
    is the tracker's, and bars that never flag leave only the limbs no view sees."""
    sk = human_template()
    pose = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), sk.rest_positions[0].copy(),
                    [side_view(yaw_deg=90)])
    limbs = Limbs(sk, BlobStack.of(sk.blobs))
    without = copy.deepcopy(sk)
    without.blobs = [b for b, i in zip(sk.blobs, limbs.of_blob)
                     if i < 0 or limbs.names[i] != "RightElbow"]
    frames = [[render(sk if k != 1 else without, pose, 0, noise=0.01, seed=k)
               for k in range(4)]]
    result = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                   [0, 1, 2, 3])
    rep = _report(result.frames)
    again = reflagged(rep, DOUBT, CLEAR)
    assert again == rep
    assert any(c["flag"] == UNSURE_FLAG for fr in rep["frames"] for c in fr["limbs"].values())
    never = reflagged(rep, 0.0, 0.0)
    assert {c["flag"] for fr in never["frames"] for c in fr["limbs"].values()} <= {"", UNSEEN}


def test_a_flag_is_carried_to_the_next_frame_and_a_given_frame_starts_afresh():
    def frame(conf):
        return {"limbs": {} if conf is None else {
            "Arm": {"confidence": conf, "views": [conf], "flag": "?"},
            "Leg": {"confidence": 0.0, "views": [None], "flag": "?"}}}

    rep = {"frames": [frame(None), frame(0.3), frame(0.9), frame(0.95), frame(None),
                      frame(0.9)]}
    got = reflagged(rep, 0.5, 0.93)
    arm = [fr["limbs"].get("Arm", {}).get("flag") for fr in got["frames"]]
    assert arm == [None, UNSURE_FLAG, UNSURE_FLAG, "", None, ""]
    assert all(fr["limbs"]["Leg"]["flag"] == UNSEEN for fr in got["frames"] if fr["limbs"])
    assert rep["frames"][1]["limbs"]["Arm"]["flag"] == "?"  # the report itself is kept


def test_the_unexplained_foreground_discounts_the_confidence_the_flag_reads():
    rep = {"frames": [{"limbs": {"Arm": {"confidence": 0.5, "views": [0.5], "flag": "?",
                                         "unexplained": 1.0}}}]}
    for weight, flag in ((0.0, ""), (0.4, ""), (0.5, UNSURE_FLAG), (1.0, UNSURE_FLAG)):
        got = reflagged(rep, 0.35, 0.9, weight)  # 0.5 / (1 + weight) against 0.35
        assert got["frames"][0]["limbs"]["Arm"]["flag"] == flag, weight


def test_the_reports_read_are_the_default_settings_of_each_start(tmp_path, monkeypatch):
    """A run's reports tracked with other settings (their names carry them), on another run
    or on other footage (halved, its exposure drifting) are passed over; each default one is
    read with the frame it started from, and the halved footage's when asked for."""
    import flag_bars
    from suite_footage import HALF

    clip = tmp_path / "cmu_131_walk"
    clip.mkdir()
    for tail in ("", "__from_1", "__from_2", "__settings_0ba07c8d", "__settings_0ba07c8d__from_1",
                 "__hand"):
        (clip / f"muybridge__3_views_15_fps{tail}.report.json").write_text("{}")
    (clip / "muybridge__3_views_30_fps.report.json").write_text("{}")
    for look in ("muybridge_half", "muybridge_drift"):
        (clip / f"{look}__3_views_15_fps.report.json").write_text("{}")
    monkeypatch.setattr(flag_bars, "CACHE", tmp_path)
    got = flag_bars.run_reports("3 views 15 fps")
    assert [(job.name, start) for job, start in got] == [
        ("muybridge__3_views_15_fps.json", 0), ("muybridge__3_views_15_fps__from_1.json", 1),
        ("muybridge__3_views_15_fps__from_2.json", 2)]
    assert flag_bars.run_reports("3 views 15 fps", ["CMU 05-01 walk"]) == []
    assert [(job.name, start) for job, start in
            flag_bars.run_reports("3 views 15 fps", footage=HALF)] == [
        ("muybridge_half__3_views_15_fps.json", 0)]
