"""Per-limb confidence: which limb a blob belongs to, each view's agreement against a loop
over the pixels, and a limb the footage no longer shows flagged by the real tracker."""

import copy

import numpy as np
import pytest

from core import confidence
from core import silhouette as sil
from core.confidence import (
    CLEAR,
    DOUBT,
    MIN_LIMB_POINTS,
    ONE_VIEW_FLAG,
    UNSEEN,
    UNSURE_FLAG,
    LimbCheck,
    Limbs,
    begun_list,
    frame_list,
)
from core.frame_fit import FrameResult
from core.linearize import Kinematics
from core.pose import CALIBRATED, BodyPose
from core.raycast import BlobStack
from core.settings import TrackerSettings
from core.skeleton import human_template
from core.tracker import Tracker, doubts_begun, frames_to_check, track
from support.synthetic import render, side_view


@pytest.fixture(scope="module")
def template():
    return human_template()


def _limbs(sk):
    return Limbs(sk, BlobStack.of(sk.blobs))


def test_a_blob_belongs_to_the_deepest_tracked_joint_that_moves_it(template):
    sk = template
    limbs = _limbs(sk)
    moved = sk.moved_by()
    tracked = set(sk.tracked_joint_names())
    assert set(limbs.names) <= tracked
    for b, blob in enumerate(sk.blobs):
        above = [sk.names[j] for j in sk.ancestors(blob.joint) if sk.names[j] in tracked]
        if not above:
            assert limbs.of_blob[b] == -1  # the trunk: the root's
        else:
            name = limbs.names[limbs.of_blob[b]]
            assert name == above[0]  # ancestors run from the blob's joint up
            assert moved[blob.joint, sk.index(name)]


def test_view_agreement_is_each_seen_limbs_mean_support_times_its_bone_on_the_silhouette(
        template):
    limbs = _limbs(template)
    L, B = len(limbs), len(template.blobs)
    rng = np.random.default_rng(3)
    blob = rng.integers(0, B, 600)
    support = rng.uniform(0, 1, 600)
    support[rng.uniform(size=600) < 0.3] = np.nan
    on = (rng.uniform(size=len(limbs.axis_ref)) < 0.6).astype(float)
    on[rng.uniform(size=len(on)) < 0.2] = np.nan  # off the image
    got = limbs.view_agreement(blob, support, on)
    plain = limbs.view_agreement(blob, support)
    for i in range(L):
        mine = [s for b, s in zip(blob, support) if limbs.of_blob[b] == i and s == s]
        bone = [x for x, k in zip(on, limbs.axis_limb) if k == i and x == x]
        if len(mine) < MIN_LIMB_POINTS:
            assert np.isnan(got[i]) and np.isnan(plain[i])
            continue
        assert plain[i] == pytest.approx(np.mean(mine))
        share = np.mean(bone) if bone else 1.0
        assert got[i] == pytest.approx(np.mean(mine) * share)


def test_a_limbs_bone_runs_along_its_blobs_long_axes(template):
    """The bone's points lie on each limb blob's long axis, inside the blob."""
    limbs = _limbs(template)
    stack = BlobStack.of(template.blobs)
    for i, name in enumerate(limbs.names):
        pts = limbs.axis_ref[limbs.axis_limb == i]
        blobs = np.flatnonzero(limbs.of_blob == i)
        assert len(pts) == len(blobs) * 9
        for b in blobs:  # every blob's own points: inside it, on one line through its centre
            u = np.einsum("ab,na->nb", stack.to_unit[b], pts - stack.centre[b])
            mine = np.linalg.norm(u, axis=1) < 1
            assert mine.sum() >= 9
            rank = np.linalg.matrix_rank(pts[mine][:9] - stack.centre[b], tol=1e-9)
            assert rank == 1, name


def test_a_bone_point_is_off_the_body_where_no_body_pixel_lies_within_its_blobs_thickness(
        template):
    """Checked point by point against a brute-force nearest body pixel, on a foreground map
    whose body pixels (foreground or unsure) are a random half of a box over the image's left
    half: the limbs on the right lie outside it, those on the left inside, among holes."""
    sk = template
    limbs = _limbs(sk)
    view = side_view(yaw_deg=0)
    pose = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), sk.rest_positions[0].copy(),
                    [view])
    kin = Kinematics(sk, pose)
    rng = np.random.default_rng(5)
    fg = np.full((360, 320), sil.BACKDROP, np.uint8)
    fg[40:330, 40:150] = rng.choice([sil.FOREGROUND, sil.UNSURE, sil.BACKDROP], (290, 110),
                                    p=[0.4, 0.1, 0.5])
    far = sil.distance_to_body(fg)
    body = np.argwhere(fg != sil.BACKDROP)  # (row, col)
    got = limbs.bone_off_body(kin, [view, view], [far, None])
    assert np.all(np.isnan(got[:, 1]))
    px = np.rint(view.project(kin.world_points(limbs.axis_joint, limbs.axis_ref))).astype(int)
    for i in range(len(limbs)):
        mine = np.flatnonzero(limbs.axis_limb == i)
        off = [np.min(np.hypot(*(body - px[k, ::-1]).T))
               > limbs.axis_thickness[k] * view.scale_at(None) for k in mine]
        assert got[i, 0] == pytest.approx(np.mean(off), abs=1e-9)
    assert 0 < np.nanmax(got[:, 0]) and np.nanmin(got[:, 0]) == 0


def test_a_limb_is_as_sure_as_its_worst_seeing_view_and_unseen_when_no_view_sees_it(
        template):
    limbs = _limbs(template)
    a = np.full(len(limbs), 0.9)
    b = np.full(len(limbs), 0.9)
    a[0], b[0] = 0.8, 0.2  # one view disagrees
    a[1], b[1] = np.nan, 0.7  # seen in one view only
    a[2] = b[2] = np.nan  # seen in none
    checks = limbs.checks([a, b])
    first, second, third = (checks[n] for n in limbs.names[:3])
    assert first.confidence == pytest.approx(0.2) and first.flag == UNSURE_FLAG
    assert first.views == pytest.approx((0.8, 0.2))
    assert second.confidence == pytest.approx(0.7) and second.flag == ""
    assert second.views[0] is None
    assert third.confidence == 0.0 and third.flag == UNSEEN
    assert all(checks[n].flag == "" for n in limbs.names[3:])
    assert DOUBT > 0.2 and not any(c.doubted for c in checks.values())


@pytest.mark.parametrize("confidence, doubted, flag", [
    (DOUBT - 0.01, False, UNSURE_FLAG), (DOUBT + 0.01, False, ""),
    (DOUBT + 0.01, True, UNSURE_FLAG), (CLEAR - 0.01, True, UNSURE_FLAG),
    (CLEAR + 0.01, True, ""), (CLEAR + 0.01, False, "")])
def test_a_limb_in_doubt_stays_flagged_until_its_confidence_is_clear(confidence, doubted, flag):
    """Falling under DOUBT flags a limb; flagged on the frame before, it stays flagged up to
    CLEAR (a limb lost over the body reads fair there and is not found again by it)."""
    assert LimbCheck(confidence, (confidence, 0.95), doubted).flag == flag
    assert LimbCheck(0.0, (None, None), doubted).flag == UNSEEN


@pytest.mark.parametrize("confidence, before, flag", [
    (ONE_VIEW_FLAG[0] - 0.01, False, UNSURE_FLAG), (ONE_VIEW_FLAG[0] + 0.01, False, ""),
    (ONE_VIEW_FLAG[1] - 0.01, True, UNSURE_FLAG), (ONE_VIEW_FLAG[1] + 0.01, True, "")])
def test_one_view_flags_by_its_own_bars_and_the_tracker_doubts_by_its_own(confidence, before,
                                                                           flag):
    """With one view the report's flag enters and leaves at ONE_VIEW_FLAG's bars, each from
    its own state on the frame before, while the tracker's doubt keeps DOUBT and CLEAR;
    with two views the two are one."""
    assert DOUBT < ONE_VIEW_FLAG[0] < ONE_VIEW_FLAG[1] and CLEAR < ONE_VIEW_FLAG[1]
    one = LimbCheck(confidence, (confidence,), doubted=False, was_flagged=before)
    assert one.flag == flag and one.doubt == (UNSURE_FLAG if confidence < DOUBT else "")
    assert LimbCheck(confidence, (confidence,), doubted=before).flag == flag  # None: as doubted
    two = LimbCheck(confidence, (confidence, 0.99), doubted=False, was_flagged=before)
    assert two.flag == two.doubt == (UNSURE_FLAG if confidence < DOUBT else "")
    assert LimbCheck(0.0, (None,), was_flagged=before).flag == UNSEEN


def test_one_views_flags_follow_their_own_frame_before_and_do_not_steer_the_tracker(
        template, monkeypatch):
    """Tracked side-on in one view, with the near forearm gone for a frame: every frame's
    checks know which limbs the tracker doubted and which the report flagged on the frame
    before, apart. Flags raised to catch fair-reading limbs change what the report shows,
    not one pose: the tracker holds what it doubts, not what is flagged for a look."""
    sk = copy.deepcopy(template)
    pose = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), sk.rest_positions[0].copy(),
                    [side_view(yaw_deg=90)])
    limbs = _limbs(sk)
    without = copy.deepcopy(sk)
    without.blobs = [b for b, i in zip(sk.blobs, limbs.of_blob)
                     if i < 0 or limbs.names[i] != "RightElbow"]
    frames = [[render(sk if k != 1 else without, pose, 0, noise=0.01, seed=k)
               for k in range(4)]]

    def run():
        return track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                     [0, 1, 2, 3]).frames

    as_set = run()
    flags_as_set = sum(len(f.flagged) for f in as_set)  # read before the bars change
    monkeypatch.setattr(confidence, "ONE_VIEW_FLAG", (0.7, 0.99))
    raised = run()
    parted = 0
    for before, now in zip(raised[1:], raised[2:]):
        for name, check in now.limbs.items():
            was = before.limbs[name]
            assert check.doubted == bool(was.doubt) and check.was_flagged == bool(was.flag)
            parted += bool(was.flag) and not was.doubt
    assert parted > 0
    for a, b in zip(as_set, raised):
        np.testing.assert_array_equal(a.pose.rotations, b.pose.rotations)
        assert {n: c.doubt for n, c in a.limbs.items()} == {
            n: c.doubt for n, c in b.limbs.items()}
    assert sum(len(f.flagged) for f in raised) > flags_as_set


def test_a_limb_gone_from_the_footage_is_flagged_and_the_rest_are_not(template):
    """Three views of a still body; in the new frame the left forearm is gone from every
    view (painted as background): its pixels match no more and its outline lies off the
    silhouette; the limbs of the other side and the legs are trusted."""
    sk = copy.deepcopy(template)
    sk.limits[:] = [-np.inf, np.inf]
    views = [side_view(yaw_deg=90), side_view(yaw_deg=0), side_view(yaw_deg=60)]
    pose = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), sk.rest_positions[0].copy(),
                    views)
    limbs = _limbs(sk)
    gone = "LeftElbow"
    without = copy.deepcopy(sk)
    without.blobs = [b for b, i in zip(sk.blobs, limbs.of_blob)
                     if i < 0 or limbs.names[i] != gone]
    frames = [[render(sk, pose, c, noise=0.01, seed=c),
               render(without, pose, c, noise=0.01, seed=10 + c),
               render(without, pose, c, noise=0.01, seed=20 + c)] for c in range(3)]
    res = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                [0, 1, 2])
    assert res.frames[0].limbs == {}  # the given pose is not judged
    checks = res.frames[1].limbs
    assert set(checks) == set(limbs.names)
    assert checks[gone].flag == UNSURE_FLAG, checks[gone]
    chain = {sk.names[j] for j in sk.ancestors(sk.index(gone))}  # the upper arm shared
    for name, check in checks.items():  # its pixels and may be flagged too
        if name not in chain:
            assert check.flag == "" and check.confidence > checks[gone].confidence + 0.3, (
                name, check)
    # the next frame judges each limb knowing which were flagged on this one
    assert {n for n, c in res.frames[2].limbs.items() if c.doubted} == {
        n for n, c in checks.items() if c.flag}
    assert res.frames[2].limbs[gone].flag == UNSURE_FLAG


@pytest.mark.parametrize("frames, text", [
    ([], ""), ([4], "4"), ([3, 5, 6, 7, 8, 9, 12], "3, 5-9, 12"), ([2, 1], "1-2")])
def test_frame_lists_join_runs(frames, text):
    assert frame_list(frames) == text


def test_doubt_begins_where_a_limb_is_first_flagged_not_on_every_frame_it_stays_flagged():
    """A limb in doubt stays flagged frame after frame; where its flag begins is what to look
    at first. A frame the user gave (a correction) or that diverged flags nothing, so a flag
    after it begins again."""
    fine, doubt, unseen = LimbCheck(0.9, (0.9, 0.95)), LimbCheck(0.1, (0.1, 0.8)), \
        LimbCheck(0.0, (None, None))

    def frame(f, diverged=False, given=False, **limbs):
        return FrameResult(frame=f, pose=None, residual=0.0, iterations=1, converged=True,
                           diverged=diverged, given=given, limbs=limbs)

    results = [frame(0, given=True),
               frame(1, Arm=doubt, Leg=fine), frame(2, Arm=doubt, Leg=unseen),
               frame(3, Arm=fine, Leg=unseen), frame(4, Arm=doubt, Leg=unseen),
               frame(5, given=True), frame(6, Arm=doubt, Leg=fine),
               frame(7, diverged=True, Arm=doubt, Leg=unseen)]
    begun = doubts_begun(results)
    assert begun == {1: {"Arm": UNSURE_FLAG}, 2: {"Leg": UNSEEN}, 4: {"Arm": UNSURE_FLAG},
                     6: {"Arm": UNSURE_FLAG}}
    assert set(begun) <= set(frames_to_check(results)) == {1, 2, 3, 4, 6}
    assert begun_list(begun) == "1 Arm; 2 Leg; 4 Arm; 6 Arm"
    assert begun_list({}) == ""
