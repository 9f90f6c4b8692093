"""Per-limb confidence: which limb a blob belongs to, each view's agreement against a loop
over the pixels, and a limb the footage no longer shows flagged by the real tracker."""

import copy

import numpy as np
import pytest

from core import confidence, raycast, se3
from core import silhouette as sil
from core.confidence import (
    CLEAR,
    DOUBT,
    MIN_LIMB_POINTS,
    ONE_VIEW_FLAG,
    UNEXPLAINED_GAP,
    UNEXPLAINED_REACH,
    UNEXPLAINED_WEIGHT,
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
from core.skeleton import BALL, FIXED, HINGE, Skeleton, human_template
from core.tracker import Tracker, doubts_begun, frames_to_check, track
from support.synthetic import EXACT, render, side_view


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


def _arm_with_hand_and_head() -> Skeleton:
    """Metres, y up: a ball shoulder with a hinge elbow and a hand fixed on the forearm, and
    a ball neck with a head fixed on it."""
    names = ["Hips", "Shoulder", "Elbow", "Hand", "Neck", "Head"]
    sk = Skeleton(names=names, parents=[-1, 0, 1, 2, 0, 4],
                  offsets=[(0, 1, 0), (0.2, 0.4, 0), (0, -0.3, 0), (0, -0.27, 0), (0, 0.5, 0),
                           (0, 0.1, 0)],
                  kinds=[FIXED, BALL, HINGE, FIXED, BALL, FIXED],
                  end_sites=[[], [], [], [np.array([0, -0.12, 0])], [],
                             [np.array([0, 0.22, 0])]])
    sk.blobs = sk.default_blobs()
    return sk


def test_a_limbs_own_bone_leaves_out_what_hangs_from_a_hinges_segment_alone():
    """The forearm's limb moves the hand too, but its own bone is the forearm alone (the
    hand turns at a wrist the tracker holds); a ball's fixed child (the head on the neck)
    stays its limb's own."""
    sk = _arm_with_hand_and_head()
    limbs = _limbs(sk)
    stack = BlobStack.of(sk.blobs)
    name_of = {b: sk.names[j] for b, j in enumerate(stack.joint)}
    for b, segment in name_of.items():
        limb = limbs.of_blob[b]
        expected = {"Shoulder": "Shoulder", "Elbow": "Elbow", "Hand": "Elbow",
                    "Neck": "Neck", "Head": "Neck"}.get(segment)
        assert (limbs.names[limb] if limb >= 0 else None) == expected, segment
        own = limbs.own_blob[b]
        assert own == (-1 if segment == "Hand" else limb), segment
    assert "Hand" in name_of.values()
    assert np.array_equal(limbs.axis_own == -1, limbs.axis_joint == sk.index("Hand"))


def test_own_agreement_is_each_limbs_own_bones_mean_support_times_their_share_on_it():
    """Against a loop over the pixels and the bone's points: a hand's pixels and bone
    count for the forearm's agreement, not for its own."""
    sk = _arm_with_hand_and_head()
    limbs = _limbs(sk)
    rng = np.random.default_rng(8)
    blob = rng.integers(0, len(sk.blobs), 800)
    support = rng.uniform(0, 1, 800)
    support[rng.uniform(size=800) < 0.2] = np.nan
    on = (rng.uniform(size=len(limbs.axis_ref)) < 0.5).astype(float)
    got = limbs.view_agreement(blob, support, on, own=True)
    for i in range(len(limbs)):
        mine = [s for b, s in zip(blob, support) if limbs.own_blob[b] == i and s == s]
        bone = [x for x, k in zip(on, limbs.axis_own) if k == i]
        assert got[i] == pytest.approx(np.mean(mine) * np.mean(bone))
    elbow = limbs.names.index("Elbow")
    assert got[elbow] != pytest.approx(limbs.view_agreement(blob, support, on)[elbow])


def test_the_flag_reads_a_limbs_own_bone_and_the_doubt_all_it_moves():
    """A forearm whose hand disagrees: the tracker doubts it, the flag does not; where no
    view sees its own bone alone, the flag reads the plain confidence."""
    check = LimbCheck(0.2, (0.2, 0.9), own_views=(0.8, 0.9))
    assert check.own_confidence == pytest.approx(0.8)
    assert check.doubt == UNSURE_FLAG and check.flag == ""
    assert LimbCheck(0.8, (0.8, 0.9), own_views=(0.3, None)).flag == UNSURE_FLAG
    hidden = LimbCheck(0.2, (0.2, 0.9), own_views=(None, None))
    assert hidden.own_confidence == pytest.approx(0.2) and hidden.flag == UNSURE_FLAG
    assert hidden.flag_views == (0.2, 0.9) and check.flag_views == (0.8, 0.9)


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


def test_unexplained_foreground_near_each_limb_is_counted_cell_by_cell(template):
    """``Limbs.unexplained`` against a loop over a window of the label map: the foreground
    cells no blob covers, farther than the gap from every covered cell (the distance to each
    one), within the reach of the limb's joint, over the pixels its blobs cover when cast
    alone."""
    sk = template
    rng = np.random.default_rng(5)
    R = np.array([se3.exp_so3(rng.normal(0, 0.3, 3)) for _ in range(sk.n_joints)])
    view = side_view(yaw_deg=70)
    kin = Kinematics(sk, BodyPose(R, sk.rest_positions[0].copy(), [view]))
    limbs, grid, shape = _limbs(sk), 2, (360, 320)
    at, size = (15, 10), (160, 130)  # the window: map cells x 15.., y 10..
    labels = raycast.label_grid(view, sk.blobs, kin.segments, shape, grid).window(*at, size)
    covered = labels >= 0
    foreground = covered.copy()
    ys, xs = np.mgrid[0:size[0], 0:size[1]]
    for cx, cy, r in rng.uniform([0, 0, 3], [size[1], size[0], 12], (12, 3)):
        foreground |= (xs - cx) ** 2 + (ys - cy) ** 2 <= r * r  # patches no blob explains
    areas = raycast.outline_areas(view, sk.blobs, kin.segments)
    got = limbs.unexplained(kin, view, grid, foreground, at, labels, areas)

    cov = np.argwhere(covered)
    loose = [(y, x) for y, x in np.argwhere(foreground & ~covered)
             if np.min(np.hypot(*(cov - (y, x)).T)) > UNEXPLAINED_GAP]
    M = sk.joint_frames(R, sk.rest_positions[0])
    g = kin.segments
    for i, name in enumerate(limbs.names):
        joint = view.project(M[sk.index(name)][:3, 3][None])[0] / grid
        mine = [b for b, k in enumerate(limbs.of_blob) if k == i]
        far = 0.0
        for b in mine:  # the blob's long axis, AXIS_REACH of its long radius either way
            blob = sk.blobs[b]
            k = int(np.argmax(blob.radii))
            for t in (-confidence.AXIS_REACH, confidence.AXIS_REACH):
                ref = blob.centre + t * blob.radii[k] * blob.Q[:, k]
                X = g[blob.joint, :3, :3] @ ref + g[blob.joint, :3, 3]
                far = max(far, float(np.linalg.norm(view.project(X[None])[0] / grid - joint)))
        near = sum(np.hypot(x + at[0] - joint[0], y + at[1] - joint[1])
                   <= UNEXPLAINED_REACH * far for y, x in loose)
        own = sum(len(raycast.render_labels(view, [sk.blobs[b]], g, shape)[0]) for b in mine)
        assert got[i] == pytest.approx(near * grid**2 / own, rel=0.06, abs=1e-9), name
    assert np.count_nonzero(got) >= 3  # the patches lie near some limbs, not all


@pytest.mark.parametrize("confidence, doubted, flag", [
    (DOUBT - 0.01, False, UNSURE_FLAG), (DOUBT + 0.01, False, ""),
    (DOUBT + 0.01, True, UNSURE_FLAG), (CLEAR - 0.01, True, UNSURE_FLAG),
    (CLEAR + 0.01, True, ""), (CLEAR + 0.01, False, "")])
def test_a_limb_in_doubt_stays_flagged_until_its_confidence_is_clear(confidence, doubted, flag):
    """Falling under DOUBT flags a limb; flagged on the frame before, it stays flagged up to
    CLEAR (a limb lost over the body reads fair there and is not found again by it)."""
    assert LimbCheck(confidence, (confidence, 0.95), doubted).flag == flag
    assert LimbCheck(0.0, (None, None), doubted).flag == UNSEEN


@pytest.mark.parametrize("unexplained", [0.0, 0.4, 1.5])
@pytest.mark.parametrize("confidence", [DOUBT - 0.01, DOUBT + 0.01, 0.6, CLEAR - 0.01,
                                        CLEAR + 0.01])
@pytest.mark.parametrize("before", [False, True])
def test_one_view_flags_what_its_unexplained_foreground_discounts_the_tracker_doubts_plainly(
        confidence, unexplained, before):
    """With one view the report's flag reads the confidence over one plus
    UNEXPLAINED_WEIGHT times the unexplained foreground, at the tracker's bars, from its own
    state on the frame before; the tracker's doubt reads the plain confidence; with two views
    the flag reads the plain confidence from its own state, whatever the foreground."""
    read = confidence / (1 + UNEXPLAINED_WEIGHT * unexplained)
    one = LimbCheck(confidence, (confidence,), doubted=False, was_flagged=before,
                    unexplained=unexplained)
    assert one.flag_confidence == pytest.approx(read)
    assert one.flag == (UNSURE_FLAG if read < (CLEAR if before else DOUBT) else "")
    assert one.doubt == (UNSURE_FLAG if confidence < DOUBT else "")
    assert LimbCheck(confidence, (confidence,), doubted=before,
                     unexplained=unexplained).flag == one.flag  # None: as doubted
    two = LimbCheck(confidence, (confidence, 0.99), doubted=before, was_flagged=False,
                    unexplained=unexplained)  # its own frame before, no foreground counted
    assert two.flag == (UNSURE_FLAG if confidence < DOUBT else "")
    assert LimbCheck(0.0, (None,), was_flagged=before, unexplained=unexplained).flag == UNSEEN


@pytest.mark.parametrize("confidence, before, flag", [
    (ONE_VIEW_FLAG[0] - 0.01, False, UNSURE_FLAG), (ONE_VIEW_FLAG[0] + 0.01, False, ""),
    (ONE_VIEW_FLAG[1] - 0.01, True, UNSURE_FLAG), (ONE_VIEW_FLAG[1] + 0.01, True, "")])
def test_one_view_without_a_backdrop_flags_at_its_own_higher_bars(confidence, before, flag):
    """Where one view has no backdrop to show what no blob explains (None), its flag reads
    the plain confidence under ONE_VIEW_FLAG's bars, above the tracker's."""
    assert DOUBT < ONE_VIEW_FLAG[0] < ONE_VIEW_FLAG[1] and CLEAR < ONE_VIEW_FLAG[1]
    one = LimbCheck(confidence, (confidence,), was_flagged=before, unexplained=None)
    assert one.flag == flag and one.flag_confidence == confidence


def test_a_one_view_track_without_its_silhouette_knows_no_unexplained_foreground(template):
    """The silhouette off, no backdrop: every check's unexplained foreground is None (not
    known), so the flags read ONE_VIEW_FLAG's bars."""
    sk = copy.deepcopy(template)
    pose, frames = _swung_forearm(sk, 2)
    res = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0, silhouette=0)),
                pose, [0, 1])
    assert res.frames[1].limbs and all(c.unexplained is None
                                       for c in res.frames[1].limbs.values())


def _swung_forearm(sk, frames: int, degrees: float = 80.0):
    """One side view of the body standing still, its near forearm swung ``degrees`` in the
    image from the second of ``frames`` frames on: the first pose, and the footage."""
    view = side_view(yaw_deg=90)
    still = np.tile(np.eye(3), (sk.n_joints, 1, 1))
    pose = BodyPose(still, sk.rest_positions[0].copy(), [view])
    swung = still.copy()
    swung[sk.index("RightElbow")] = se3.exp_so3(view.pose.R[2] * np.radians(degrees))
    moved = BodyPose(swung, pose.root_position, [view])
    return pose, [[render(sk, pose if k == 0 else moved, 0, noise=0.01, seed=k)
                   for k in range(frames)]]


def test_one_views_flags_follow_their_own_frame_before_and_do_not_steer_the_tracker(
        template, monkeypatch):
    """Tracked side-on in one view, with the near forearm swung beyond the fit's reach: every
    frame's checks know which limbs the tracker doubted and which the report flagged on the
    frame before, apart. The unexplained foreground weighed far more changes what the report
    shows, not one pose: the tracker holds what it doubts, not what is flagged for a look."""
    sk = copy.deepcopy(template)
    pose, frames = _swung_forearm(sk, 4)

    def run():
        return track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                     [0, 1, 2, 3]).frames

    as_set = run()
    flags_as_set = sum(len(f.flagged) for f in as_set)  # read before the bars change
    monkeypatch.setattr(confidence, "UNEXPLAINED_WEIGHT", 1e3)
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


def test_one_view_flags_a_forearm_left_behind_where_its_pixels_lie_unexplained(template):
    """One view, a forearm swung 80 degrees in the image between two frames, too far for the
    fit to follow (no search): the forearm's own pixels are foreground no blob explains,
    beside where it is tracked, more than near any other limb, and the flag reads its
    confidence over one plus that, weighed. The shins, far from them, have none."""
    sk = copy.deepcopy(template)
    pose, frames = _swung_forearm(sk, 3)
    swung = se3.exp_so3(pose.views[0].pose.R[2] * np.radians(80))
    res = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                [0, 1, 2])
    tracked = res.frames[1].pose.rotations[sk.index("RightElbow")]
    assert np.degrees(se3.rotation_angle_between(tracked, swung)) > 40
    checks = res.frames[1].limbs
    arm = checks["RightElbow"]
    assert arm.unexplained > 0.2 and arm.flag == UNSURE_FLAG, arm
    assert arm.flag_confidence == pytest.approx(
        arm.confidence / (1 + confidence.UNEXPLAINED_WEIGHT * arm.unexplained))
    assert arm.unexplained == max(c.unexplained for c in checks.values())
    for shin in ("LeftKnee", "RightKnee"):  # the forearm's pixels are beyond their reach
        assert checks[shin].unexplained == 0.0, checks[shin]


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
    res = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0, **EXACT)), pose,
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


def test_a_hand_turned_at_its_held_wrist_is_doubted_by_the_tracker_not_flagged():
    """Three views of an arm whose hand turns 70 degrees at the wrist from the second frame
    on, tracked by the real tracker with the wrist held: the forearm stays where it is, its
    hand's pixels and bone disagree, so the tracker doubts the limb (it lets go of them),
    while its own bone agrees and the report does not flag it."""
    sk = _arm_with_hand_and_head()
    views = [side_view(yaw_deg=90), side_view(yaw_deg=0), side_view(yaw_deg=60)]
    still = np.tile(np.eye(3), (sk.n_joints, 1, 1))
    pose = BodyPose(still, sk.rest_positions[0].copy(), views)
    bent = still.copy()
    bent[sk.index("Hand")] = se3.exp_so3(np.array([np.radians(70), 0, 0]))
    moved = BodyPose(bent, pose.root_position, views)
    frames = [[render(sk, pose if k == 0 else moved, c, noise=0.01, seed=10 * k + c)
               for k in range(3)] for c in range(3)]
    res = track(Tracker(sk, frames, CALIBRATED, TrackerSettings(limb_search=0)), pose,
                [0, 1, 2])
    for fr in res.frames[1:]:
        elbow = fr.pose.rotations[sk.index("Elbow")]
        assert np.degrees(se3.rotation_angle_between(elbow, np.eye(3))) < 2
        arm = fr.limbs["Elbow"]
        assert arm.doubt == UNSURE_FLAG and arm.flag == "", arm
        assert arm.own_confidence > arm.confidence + 0.2
        assert "Elbow" not in fr.flagged


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
