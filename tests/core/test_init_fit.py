"""Fitting the first frame's pose and the body's proportions to clicked joints."""

from pathlib import Path

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh
from core.camera import Pinhole, View
from core.init_fit import FitError, fit_pose, least_certain, symmetry_key
from core.pose import CALIBRATED, INDEPENDENT, BodyPose
from core.skeleton import BALL, HINGE, Skeleton, human_template, skeleton_from_bvh, twist_about

JOINTS = {"LeftHip": BALL, "RightHip": BALL, "LeftShoulder": BALL, "RightShoulder": BALL,
          "Neck": BALL, "LeftKnee": (HINGE, [0.94, 0.34, 0]),
          "RightKnee": (HINGE, [0.94, -0.34, 0]), "LeftElbow": (HINGE, [0.87, 0, -0.5]),
          "RightElbow": (HINGE, [0.87, 0, 0.5])}
CLICKED = ["Hips", "LeftHip", "RightHip", "LeftKnee", "RightKnee", "LeftAnkle", "RightAnkle",
           "LeftToe", "RightToe", "LeftShoulder", "RightShoulder", "LeftElbow", "RightElbow",
           "LeftWrist", "RightWrist", "Neck", "Head"]
LIMBS = [("LeftHip", "LeftKnee"), ("RightHip", "RightKnee"), ("LeftKnee", "LeftAnkle"),
         ("RightKnee", "RightAnkle"), ("LeftShoulder", "LeftElbow"),
         ("RightShoulder", "RightElbow"), ("LeftElbow", "LeftWrist"),
         ("RightElbow", "RightWrist")]


def _views(n, pinhole=False):
    """Views of a body 700 px tall: scaled orthographic, or pinholes 2.5 m away."""
    out = []
    for yaw in [90, 0, 60][:n]:
        R = np.diag([1.0, -1, -1]) @ se3.exp_so3(np.radians([0, yaw, 0]))
        if pinhole:
            K = np.array([[1000.0, 0, 540], [0, 1000.0, 540], [0, 0, 1]])
            out.append(Pinhole(K, R, -R @ [0.3, 0.9, -1.5] + [0, 0, 2.5]))
        else:
            out.append(View(se3.Similarity(400.0, R, -R @ [0.3, 0.9, -1.5] + [0, 0, 5]),
                            np.array([540.0, 540.0])))
    return out


def _body(cmu_walk):
    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    for name, spec in JOINTS.items():
        j = sk.index(name)
        sk.kinds[j] = spec if isinstance(spec, str) else spec[0]
        if not isinstance(spec, str):
            sk.axes[j] = np.array(spec[1]) / np.linalg.norm(spec[1])
    return b, sk


def _representable(sk, R_guess, R, p):
    """The pose R, p as the fit can hold it: untracked joints as in the guess, hinges turned
    about their axis from the guess."""
    out = R_guess.copy()
    out[0] = R[0]
    for j, kind in enumerate(sk.kinds):
        if kind == BALL:
            out[j] = R[j]
        elif kind == HINGE:
            theta = se3.log_so3(R_guess[j].T @ R[j]) @ sk.axes[j]
            out[j] = R_guess[j] @ se3.exp_so3(sk.axes[j] * theta)
    return out, p


def _scaled(sk, rng):
    """The same skeleton with every bone pair's length changed by up to 8 %."""
    factor = {}
    offsets = sk.offsets.copy()
    for j in range(1, sk.n_joints):
        f = factor.setdefault(symmetry_key(sk.names[j]), rng.uniform(0.92, 1.08))
        offsets[j] *= f
    return Skeleton(sk.names, sk.parents, offsets, sk.kinds, sk.axes, sk.end_sites)


def _clicks(true_sk, R, p, views, rng, noise=1.0):
    X = true_sk.world_positions(R, p)
    out = []
    for c, v in enumerate(views):
        names = [n for i, n in enumerate(CLICKED) if (i + c) % 7]  # each joint missing once
        out.append({n: v.project(X[true_sk.index(n)]) + rng.normal(0, noise, 2) for n in names})
    return out


@pytest.mark.parametrize("mode, pinhole", [(CALIBRATED, False), (INDEPENDENT, False),
                                           (CALIBRATED, True)])
@pytest.mark.parametrize("noise, seed", [(0.0, 0), (1.0, 0), (1.0, 5), (2.0, 0)])
def test_recovers_limb_directions_and_lengths_from_three_views(cmu_walk, mode, pinhole, noise,
                                                               seed):
    b, guess_sk = _body(cmu_walk)
    rng = np.random.default_rng(seed)
    true_sk = _scaled(guess_sk, rng)
    R_guess, p_guess = b.frame_pose(590)  # a nearby frame of the walk: the starting guess
    R_true, p_true = _representable(guess_sk, R_guess, *b.frame_pose(600))
    views = _views(3, pinhole)
    clicks = _clicks(true_sk, R_true, p_true, views, rng, noise)
    res = fit_pose(guess_sk, BodyPose(R_guess, p_guess, views), clicks, mode)
    X = true_sk.world_positions(R_true, p_true)
    Y = res.skeleton.world_positions(res.pose.rotations, res.pose.root_position)
    if mode == INDEPENDENT:  # compare in the first view's frame, which fixes the root
        X = X @ views[0].pose.R.T
        Y = Y @ res.pose.views[0].pose.R.T
    errs, lens = [], []
    for a, c in LIMBS:
        ia, ic = true_sk.index(a), true_sk.index(c)
        errs.append(np.degrees(se3.angle_between_vectors(Y[ic] - Y[ia], X[ic] - X[ia])))
        lens.append(np.linalg.norm(res.skeleton.offsets[ic]) / np.linalg.norm(
            true_sk.offsets[ic]) - 1)
    for left, right in [("LeftKnee", "RightKnee"), ("LeftElbow", "RightElbow")]:
        assert res.lengths[left] == res.lengths[right]  # symmetry holds exactly
    # the two chest bones meet at no click and no branch, so only their sum shows: one
    # factor for both (apart, at 1 px noise six seeds of ten pushed one to its 0.5 bound and
    # the other up by 40-80 %)
    assert res.lengths["Chest"] == res.lengths["Chest2"]
    assert all(abs(f - 1) < 0.15 for f in res.lengths.values()), res.lengths
    if mode == INDEPENDENT:  # the body's size, which the views' scales take, stays about
        # the guess's: within 3 % over seeds 0-9, whose true bones differ from it by up to
        # 8 % (with the chest bones apart, seeds 5, 7 and 8 fitted a body 11-16 % taller)
        assert abs(res.skeleton.height() / guess_sk.height() - 1) < 0.05
    ratio = 1 + np.array(lens)  # fitted over true lengths
    if mode == INDEPENDENT:  # each view's own scale takes the body's size: only its
        ratio /= ratio.mean()  # proportions are fixed by the clicks
    if noise == 0:  # exact clicks: the fit is exact
        assert np.max(errs) < 0.05 and np.max(np.abs(ratio - 1)) < 1e-3, (errs, lens)
        assert res.residual_px < 0.05  # 0.012: the truth's chest bones differ, the fit's not
        return
    # measured at 1 px click noise on a 700-pixel body over seeds 0-9: mean 0.7 (calibrated)
    # and 0.9 (independent) degrees, worst limb 1.2-2.8; the issue asks for every limb within
    # 2 degrees and 2 %. The worst is the left forearm, 74 px long, whose wrist is missing in
    # one view while the other two are 30 degrees apart: the click noise carried through the
    # fit (finite differences of the fitted direction in every click coordinate) gives it
    # 1.9 degrees RMS at 1 px, the other limbs 0.4-1.7, so a 2-degree bound on every limb of
    # every seed is more than these clicks hold. Lengths over the same seeds: within 1.4 %
    # (calibrated); independent views fit the body's size freely (0-19 % over) but its
    # proportions within 1 %. The errors grow with the noise: at 2 px over the same seeds,
    # mean 1.4 (calibrated) and 1.8 (independent) degrees, worst limb 1.9-5.5, lengths and
    # proportions within 2.6 %
    # pinholes 2.5 m away, calibrated, 1 px over seeds 0-9: mean 0.6 degrees, worst limb
    # 0.8-3.8 (the far side of the body is smaller in the image than the near side)
    worst = 4.0 if pinhole else 3.0
    assert np.mean(errs) < 1.5 * noise and np.max(errs) < worst * noise, errs
    assert np.max(np.abs(ratio - 1)) < 0.02 * noise, lens
    assert res.residual_px < 2 * noise


def test_each_limbs_reported_uncertainty_is_the_scatter_of_its_fit_over_click_noise(cmu_walk):
    # the fit reports, per bone, the RMS direction error that its information matrix bounds
    # for a pixel of click error. Checked against the fit itself: the same body and clicks
    # refitted under sixteen draws of 1 px noise scatter each limb's direction by what was
    # reported (measured: ratios 0.91-1.28 by limb, 1.08 pooled; 0.94-1.15 and 1.02 for
    # other draws), so the fit gets out of the clicks what they hold and no more can be had
    b, guess_sk = _body(cmu_walk)
    true_sk = _scaled(guess_sk, np.random.default_rng(0))
    R_guess, p_guess = b.frame_pose(590)
    R_true, p_true = _representable(guess_sk, R_guess, *b.frame_pose(600))
    views = _views(3)
    X = true_sk.world_positions(R_true, p_true)
    errs, reported = [], []
    for seed in range(16):
        clicks = _clicks(true_sk, R_true, p_true, views, np.random.default_rng(100 + seed))
        res = fit_pose(guess_sk, BodyPose(R_guess, p_guess, views), clicks, CALIBRATED)
        Y = res.skeleton.world_positions(res.pose.rotations, res.pose.root_position)
        errs.append([np.degrees(se3.angle_between_vectors(
            Y[true_sk.index(c)] - Y[true_sk.index(a)], X[true_sk.index(c)] - X[true_sk.index(a)]))
            for a, c in LIMBS])
        reported.append([res.direction_uncertainty[a] for a, _ in LIMBS])
    scatter = np.sqrt(np.mean(np.square(errs), axis=0))
    bound = np.mean(reported, axis=0)
    assert np.all((scatter > 0.6 * bound) & (scatter < 1.6 * bound)), (scatter, bound)
    pooled = np.sqrt(np.mean(np.square(errs)) / np.mean(np.square(reported)))
    assert 0.85 < pooled < 1.25, pooled
    # the forearm whose wrist one view misses is the least certain limb, and at 1 px more
    # than the 2 degrees the issue asks of every limb
    assert max(bound) == bound[LIMBS.index(("LeftElbow", "LeftWrist"))] > 1.7

    # fewer views hold less: one view, lengths known, reports every limb less certain,
    # some of them by far (the turn toward the camera shows only in foreshortening)
    clicks = _clicks(true_sk, R_true, p_true, views[:1], np.random.default_rng(100))
    one = fit_pose(true_sk, BodyPose(R_guess, p_guess, views[:1]), clicks, CALIBRATED,
                   fit_lengths=False).direction_uncertainty
    one = np.array([one[a] for a, _ in LIMBS])
    assert np.all(one > bound) and max(one) > 5 * max(bound), one


def test_one_view_with_known_lengths_recovers_each_clicked_limb_up_to_its_mirror_in_depth(
        cmu_walk):
    # one orthographic view shows a limb's image and, given its length, the size of its depth
    # component but not its sign: a limb pointing 10 degrees toward the camera looks like one
    # pointing 10 degrees away. Lengths cannot be fitted from one view (a longer limb turned
    # further out of the image plane looks the same), so they are given
    b, sk = _body(cmu_walk)
    R_guess, p_guess = b.frame_pose(590)
    R_true, p_true = _representable(sk, R_guess, *b.frame_pose(600))
    views = _views(1)
    clicks = _clicks(sk, R_true, p_true, views, np.random.default_rng(0), noise=0.0)
    res = fit_pose(sk, BodyPose(R_guess, p_guess, views), clicks, CALIBRATED, fit_lengths=False)
    assert res.residual_px < 0.1
    Rc = views[0].pose.R  # compare in the camera's frame, z along the view
    X = sk.world_positions(R_true, p_true) @ Rc.T
    Y = res.skeleton.world_positions(res.pose.rotations, res.pose.root_position) @ Rc.T
    checked, mirrored = 0, 0
    for a, c in LIMBS:
        if a not in clicks[0] or c not in clicks[0]:
            continue  # an end not clicked in the one view: nothing pins the limb
        ia, ic = sk.index(a), sk.index(c)
        true, got = X[ic] - X[ia], Y[ic] - Y[ia]
        err = [np.degrees(se3.angle_between_vectors(got, t)) for t in (true, true * [1, 1, -1])]
        assert min(err) < 0.5, (a, c, err)
        checked += 1
        mirrored += err[1] < err[0]
    assert checked >= 6
    # the ambiguity is real here: the starting guess put some limbs on the other side
    assert mirrored >= 1


@pytest.mark.parametrize("seed", [0, 3])
def test_one_view_with_click_noise_recovers_each_limb_in_the_image_plane(cmu_walk, seed):
    # at 1 px noise one view holds each clicked limb's direction in its image plane; its tilt
    # out of that plane comes from the limb's foreshortening, which a pixel moves by degrees
    # (up to 10 over seeds 0-4 for a limb 73-164 px long), so only the image plane is held
    # to 2 degrees (measured: at most 1.1 over seeds 0-4)
    b, sk = _body(cmu_walk)
    R_guess, p_guess = b.frame_pose(590)
    R_true, p_true = _representable(sk, R_guess, *b.frame_pose(600))
    views = _views(1)
    clicks = _clicks(sk, R_true, p_true, views, np.random.default_rng(seed), noise=1.0)
    res = fit_pose(sk, BodyPose(R_guess, p_guess, views), clicks, CALIBRATED, fit_lengths=False)
    assert res.residual_px < 2
    Rc = views[0].pose.R  # the camera's frame: x, y in the image plane
    X = sk.world_positions(R_true, p_true) @ Rc.T
    Y = res.skeleton.world_positions(res.pose.rotations, res.pose.root_position) @ Rc.T
    checked = 0
    for a, c in LIMBS:
        if a in clicks[0] and c in clicks[0]:
            ia, ic = sk.index(a), sk.index(c)
            true, got = X[ic, :2] - X[ia, :2], Y[ic, :2] - Y[ia, :2]
            turn = np.degrees(abs(np.angle(complex(*got) / complex(*true))))
            assert turn < 2.0, (a, c, turn)
            checked += 1
    assert checked >= 6


def test_the_fit_command_writes_fitted_offsets_and_pose(cmu_walk, tmp_path):
    import json
    import re
    import subprocess
    import sys

    b, guess_sk = _body(cmu_walk)
    rng = np.random.default_rng(5)
    true_sk = _scaled(guess_sk, rng)
    R_guess, p_guess = b.frame_pose(590)
    R_true, p_true = _representable(guess_sk, R_guess, *b.frame_pose(600))
    views = _views(3)
    clicks = _clicks(true_sk, R_true, p_true, views, rng, noise=0.0)
    b.motion = b.motion[590:591]
    from core.bvh import write_bvh

    write_bvh(b, tmp_path / "guess.bvh")
    fit = {"skeleton": {"bvh": "guess.bvh", "joints": {
               n: s if isinstance(s, str) else {"kind": s[0], "axis": s[1]}
               for n, s in JOINTS.items()}},
           "initial": {"bvh": "guess.bvh", "frame": 0},
           "views": [{"camera": {"model": "scaled_orthographic", "R": v.pose.R.tolist(),
                                 "t": v.pose.t.tolist(), "scale": v.pose.s,
                                 "center": v.center.tolist()}} for v in views],
           "mode": "calibrated",
           "clicks": [{n: list(map(float, p)) for n, p in c.items()} for c in clicks]}
    (tmp_path / "fit.json").write_text(json.dumps(fit))
    root = Path(__file__).resolve().parents[2]
    proc = subprocess.run([sys.executable, "-m", "core", "fit", str(tmp_path / "fit.json"),
                           "--out", str(tmp_path / "fitted.bvh")], cwd=root,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    # the bones the clicks pin least: the neck's (its ends 9 cm apart) and the forearm whose
    # wrist one view misses
    assert re.search(r"least certain bones: Neck \+-2\.\d, LeftElbow \+-1\.\d, "
                     r"RightElbow \+-1\.\d degrees per pixel of click error", proc.stderr), \
        proc.stderr
    got = read_bvh(tmp_path / "fitted.bvh")
    assert len(got.motion) == 1 and got.names == b.names
    fitted = skeleton_from_bvh(got)
    R, p = got.frame_pose(0)
    np.testing.assert_allclose(fitted.world_positions(R, p)[[true_sk.index(n) for n in CLICKED]],
                               true_sk.world_positions(R_true, p_true)[
                                   [true_sk.index(n) for n in CLICKED]], atol=5e-3)
    # (5 mm: unclicked bones share one length factor, the truth gave each its own)
    bad = dict(fit, clicks=fit["clicks"][:2])
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    proc = subprocess.run([sys.executable, "-m", "core", "fit", str(tmp_path / "bad.json"),
                           "--out", str(tmp_path / "x.bvh")], cwd=root, capture_output=True,
                          text=True)
    assert proc.returncode == 2
    assert "bad.json.clicks: expected one object per view (3), got 2" in proc.stderr
    one = dict(fit, views=fit["views"][:1], clicks=fit["clicks"][:1])
    for name, extra, code, says in [("one.json", {}, 2, "one view cannot tell a longer bone"),
                                    ("pose.json", {"fit_lengths": False}, 0,
                                     "(its turn toward or away from the camera: one view "
                                     "shows it only as foreshortening)")]:
        (tmp_path / name).write_text(json.dumps(dict(one, **extra)))
        proc = subprocess.run([sys.executable, "-m", "core", "fit", str(tmp_path / name),
                               "--out", str(tmp_path / "x.bvh")], cwd=root,
                              capture_output=True, text=True)
        assert proc.returncode == code and says in proc.stderr + proc.stdout, proc.stderr


def test_the_least_certain_bones_are_named_apart_from_those_not_pinned():
    said = least_certain({"Neck": 2.13, "LeftElbow": 1.9, "LeftKnee": 0.4, "RightHip": 1e9,
                          "LeftShoulder": 180.0}, n=2, views=1)
    assert said == ("Neck +-2.1, LeftElbow +-1.9 degrees per pixel of click error; not "
                    "pinned: LeftShoulder, RightHip (its turn toward or away from the camera:"
                    " one view shows it only as foreshortening)")
    assert least_certain({"Neck": 1e9}) == ("not pinned: Neck (click the joints below it in "
                                            "a view)")
    assert least_certain({}) == "none turned"


def test_degenerate_clicks_get_a_clear_message(cmu_walk):
    b, sk = _body(cmu_walk)
    R, p = b.frame_pose(600)
    views = _views(1)
    X = sk.world_positions(R, p)
    few = [{n: views[0].project(X[sk.index(n)]) for n in ["Hips", "LeftKnee", "Head"]}]
    with pytest.raises(FitError, match="click at least .* more joints"):
        fit_pose(sk, BodyPose(R, p, views), few, CALIBRATED)
    line = [{n: np.array([100.0 + 10 * i, 50.0 + 20 * i]) for i, n in enumerate(CLICKED)}]
    with pytest.raises(FitError, match="view 1: the 17 clicks lie on one line"):
        fit_pose(sk, BodyPose(R, p, views), line, CALIBRATED)
    with pytest.raises(FitError, match="no joint named 'Tail'"):
        fit_pose(sk, BodyPose(R, p, views), [{"Tail": (1, 2)}], CALIBRATED)
    good = [{n: views[0].project(X[sk.index(n)]) for n in CLICKED}]
    with pytest.raises(FitError, match="one view cannot tell a longer bone"):
        fit_pose(sk, BodyPose(R, p, views), good, CALIBRATED, fit_lengths=True)


def test_the_tips_of_limbs_pin_the_bones_that_end_in_them():
    """A quadruped seen from its side: its lower legs and head end in end sites, so only
    clicks on those tips ("<joint>/end") can turn them; with the tips clicked every hinge
    comes back exactly, without them the lower legs stay as guessed."""
    from core.skeleton import planar_quadruped_template

    sk = planar_quadruped_template()
    rng = np.random.default_rng(2)
    R_true = np.tile(np.eye(3), (sk.n_joints, 1, 1))
    hinges = [j for j in range(sk.n_joints) if sk.kinds[j] == HINGE]
    for j in hinges:
        R_true[j] = se3.exp_so3(sk.axes[j] * np.radians(rng.uniform(-30, 30)))
    root = sk.rest_positions[0].copy()
    view = View(se3.Similarity(150.0, np.diag([1.0, -1, -1]), np.array([0, 0, 5.0])),
                np.array([320.0, 300.0]))
    M = sk.joint_frames(R_true, root)
    clicks = {n: view.project(M[j, :3, 3][None])[0] for j, n in enumerate(sk.names)}
    tips = {f"{n}/end": view.project((M[j, :3, :3] @ sk.end_sites[j][0] + M[j, :3, 3])[None])[0]
            for j, n in enumerate(sk.names) if sk.end_sites[j]}
    assert len(tips) == 5  # four hooves and the head
    guess = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), root, [view])
    both = fit_pose(sk, guess, [{**clicks, **tips}], CALIBRATED, fit_lengths=False)
    joints_only = fit_pose(sk, guess, [clicks], CALIBRATED, fit_lengths=False)
    assert both.residual_px < 0.05
    # one orthographic view cannot see the body's depth: the fit leaves it where it was
    # (its float32 copy in Blender lost pixels once it had slid kilometres away)
    np.testing.assert_allclose(both.pose.root_position, root, atol=1e-3)
    for j in hinges:
        err = np.degrees(se3.rotation_angle_between(both.pose.rotations[j], R_true[j]))
        assert err < 0.1, sk.names[j]
    lower = [j for j in hinges if sk.end_sites[j] and sk.names[j] != "Head"]
    missed = [np.degrees(se3.rotation_angle_between(joints_only.pose.rotations[j], R_true[j]))
              for j in lower]
    assert max(missed) > 10  # nothing else can turn them
    with pytest.raises(FitError, match="'Trunk' has no end site"):
        fit_pose(sk, guess, [{**clicks, "Trunk/end": (0.0, 0.0)}], CALIBRATED,
                 fit_lengths=False)


def test_a_knee_fitted_bent_forward_under_a_thigh_twisted_half_a_turn_comes_back_untwisted():
    # the guess's thigh twisted half a turn: the clicks of a knee bent 40 degrees are met
    # as well by that thigh over the knee bent forward, outside the knee's limits, where a
    # tracker could only straighten it; the fit returns the same body within them
    sk = human_template()
    knee, hip = sk.index("LeftKnee"), sk.index("LeftHip")
    along = sk.offsets[knee] / np.linalg.norm(sk.offsets[knee])
    R_true = np.repeat(np.eye(3)[None], sk.n_joints, 0)
    R_true[hip] = se3.exp_so3(np.radians([-25.0, 0, 5]))
    R_true[knee] = se3.exp_so3(np.radians(40.0) * sk.axes[knee])
    p = np.array([0.3, 0.0, -1.5])
    views = _views(3)
    X = sk.world_positions(R_true, p)
    names = ["Hips", "LeftHip", "LeftKnee", "RightHip", "RightKnee", "LeftShoulder",
             "RightShoulder", "LeftElbow", "RightElbow", "Neck"]
    clicks = [{n: v.project(X[sk.index(n)]) for n in names} | {
        f"{n}/end": v.project(sk.joint_frames(R_true, p)[sk.index(n), :3, :3]
                              @ sk.end_sites[sk.index(n)][0]
                              + sk.joint_frames(R_true, p)[sk.index(n), :3, 3])
        for n in ("LeftKnee", "RightKnee", "LeftElbow", "RightElbow", "Neck")} for v in views]
    R_guess = R_true.copy()
    R_guess[hip] = R_true[hip] @ se3.exp_so3(np.radians(175.0) * along)
    R_guess[knee] = np.eye(3)
    res = fit_pose(sk, BodyPose(R_guess, p, views), clicks, CALIBRATED, fit_lengths=False)
    assert res.residual_px < 0.5
    R = res.pose.rotations
    assert np.degrees(sk.hinge_angle(knee, R[knee])) == pytest.approx(40, abs=1)
    assert abs(np.degrees(twist_about(R[hip], along))) < 10
