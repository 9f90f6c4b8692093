"""Where a tracked suite run loses, limb by limb and frame by frame.

    python bench/limb_errors.py JOB.json [--run "3 views 15 fps"] [--start N]
                                [--twist JOINT,...] [--heading] [--jumps DEG]
                                [--one-step {predicted,at-truth}]

For a job ``bench/suite.py`` tracked (its ``.bvh`` beside it, the clip's ``truth.bvh`` in its
folder): per frame of the run, each of the eight limbs' direction error against the capture,
and against the best fit of the tracked degrees of freedom (``suite.fitted_body``), in
degrees. With ``--twist``, each named joint's turn against the best fit, split into its twist
about the bone and its swing across it: an upper arm's twist sets the plane its elbow bends
in, which no outline of the upper arm shows (``docs/RESEARCH.md``, thirty-eighth session).
With ``--heading``, the root's turn about the vertical against the capture and the best
fit, per frame: a body that turns can keep its trunk turned right while its pelvis, seen
only by where the legs hang from it, lags, the lower back twisting to make up for it
(``docs/RESEARCH.md``, forty-third session); and how far each frame's fit turned it from
the tracker's constant-velocity prediction, beside how far the capture was from that
prediction. With ``--jumps DEG``, the frames where a limb's error against the capture rose
by more than DEG degrees in one frame, each with what moved it there: the limb search
(the run's report names the joints it turned on each frame), the search turning the limb
it hangs from, or the solver's steps alone. With ``--one-step``, every frame tracked once
more, alone, from the best fit of the frames before (``walk_benchmark.one_step_poses``;
``at-truth``: predicted at the frame's own best fit), its root's heading against the best
fit's, the share of each frame's turn it leaves undone, and each limb's mean error against
the best fit after that one step: a bias of the cost itself, apart from drift
(``docs/RESEARCH.md``, fifty-seventh and sixty-second sessions). ``--start`` is the frame
the run started from (``__from_N`` in the job's name).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from evaluate import swing_twist  # noqa: E402
from suite import RUNS, fitted_body, tracked_and_true  # noqa: E402
from walk_benchmark import one_step_poses  # noqa: E402

from core.pose import BodyPose, extrapolate  # noqa: E402


def limb_errors(job_path: Path, run: str, start: int) -> tuple:
    """The run's eight scored limbs (label, joint, end joint), and per frame their errors
    (F, 8) against the capture and against the best fit, degrees; with the job, the
    tracked, the captured and the best-fit poses."""
    job, limbs, est, truth = tracked_and_true(job_path, run, start)
    body, sight = fitted_body(job)
    best = evaluate.best_fit(body, truth, sight)
    sk = job.skeleton
    scored = limbs[:8]
    errors = []
    for ref in (truth, best):
        per = evaluate.limb_errors_deg(sk, est, ref, limbs)
        errors.append(np.stack([per[label] for label, _, _ in scored], axis=1))
    return scored, errors[0], errors[1], job, est, truth, best


def predicted_roots(roots: np.ndarray, gain: float = 1.0) -> np.ndarray:
    """The tracker's prediction (``core.pose.extrapolate``) of each frame's root rotation
    from the tracked ones before it, ``roots`` (F, 3, 3): frame 1 from frame 0 alone (its
    own rotation), every later one moved on by ``gain`` times the step between the two
    before; frame 0 is the given pose itself."""
    out = roots.copy()
    if len(roots) > 1:
        out[1] = roots[0]
    at = np.zeros(3)  # the root's position, which the rotation's prediction does not read
    for f in range(2, len(roots)):
        before, last = (BodyPose(R[None], at, []) for R in roots[f - 2:f])
        out[f] = extrapolate(before, last, gain).rotations[0]
    return out


def lag_share(beyond: np.ndarray, turn: np.ndarray) -> float:
    """The share of each frame's turn a tracked heading leaves undone: the least-squares k
    in ``beyond`` = -k ``turn`` (per frame, degrees the tracked root is turned beyond the
    reference, and the reference's own turn since the frame before); NaN where nothing
    turns."""
    den = float(turn @ turn)
    return float("nan") if den == 0 else -float(beyond @ turn) / den


def twist_rows(job, est: tuple, best: tuple, joint: str) -> np.ndarray:
    """Per frame, ``joint``'s tracked turn against the best fit's (its segment's orientation
    in the world), as (swing, twist) degrees about its bone (F, 2)."""
    sk = job.skeleton
    j = sk.index(joint)
    axis = sk.bone_frame(j)[0]
    out = []
    for f in range(len(est[0])):
        tracked = sk.joint_frames(est[0][f], est[1][f])[j][:3, :3]
        fitted = sk.joint_frames(best[0][f], best[1][f])[j][:3, :3]
        out.append(swing_twist(fitted.T @ tracked, axis))
    return np.array(out)


def jumps(limbs: list, errors: np.ndarray, searched: list, rise: float) -> list[tuple]:
    """Where a limb's error rose by more than ``rise`` degrees in one frame: (frame, limb,
    error before, error after, what moved it). ``limbs`` (label, joint, end joint) the
    scored limbs, ``errors`` (F, L) their errors, ``searched`` per frame the joints the limb
    search turned (the report's); what moved it is ``search`` where the search turned the
    limb's joint, ``search (parent)`` where it turned the joint of the limb it hangs from
    (the one ending where it starts), else ``steps``."""
    parent = {joint: next((j for _, j, end in limbs if end == joint), None)
              for _, joint, _ in limbs}
    out = []
    for f, k in np.argwhere(np.diff(errors, axis=0) > rise):
        label, joint, _ = limbs[k]
        turned = set(searched[f + 1]) if f + 1 < len(searched) else set()
        by = ("search" if joint in turned else
              "search (parent)" if parent[joint] in turned else "steps")
        out.append((int(f) + 1, label, float(errors[f, k]), float(errors[f + 1, k]), by))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("job", type=Path, help="a job bench/suite.py tracked")
    ap.add_argument("--run", default="3 views 15 fps", choices=list(RUNS))
    ap.add_argument("--start", type=int, default=0, help="the frame the run started from")
    ap.add_argument("--twist", default="", help="comma-separated joints to split")
    ap.add_argument("--heading", action="store_true",
                    help="the root's turn about the vertical against the capture and the "
                    "best fit")
    ap.add_argument("--jumps", type=float, default=0.0, metavar="DEG",
                    help="list the frames where a limb's error rose by more than DEG "
                    "degrees, and whether the limb search moved it")
    ap.add_argument("--one-step", choices=("predicted", "at-truth"),
                    help="track each frame once more from the best fit of the frames "
                    "before, and read its heading against the best fit's")
    args = ap.parse_args(argv)
    limbs, vs_truth, vs_best, job, est, truth, best = limb_errors(args.job, args.run,
                                                                   args.start)
    names = [label for label, _, _ in limbs]
    print("frame  " + "  ".join(f"{n[:12]:>12s}" for n in names) + "   (capture / best fit)")
    for f, (a, b) in enumerate(zip(vs_truth, vs_best)):
        print(f"{f:5d}  " + "  ".join(f"{x:5.1f} /{y:5.1f}" for x, y in zip(a, b)))
    print("mean   " + "  ".join(f"{x:5.1f} /{y:5.1f}" for x, y in
                                 zip(vs_truth.mean(0), vs_best.mean(0))))
    if args.heading:
        roots = [np.asarray(p[0])[:, 0] for p in (est, truth, best)]
        print("the root's turn about the vertical beyond the capture / the best fit, per "
              "frame, degrees")
        print("  ".join(f"{a:.0f}/{b:.0f}" for a, b in zip(
            evaluate.heading_errors_deg(roots[0], roots[1]),
            evaluate.heading_errors_deg(roots[0], roots[2]))))
        pred = predicted_roots(roots[0], job.settings.prediction_gain)
        print("how far each frame's fit turned it about the vertical from the prediction / "
              "how far the capture was from it, degrees")
        print("  ".join(f"{a:+.1f}/{b:+.1f}" for a, b in zip(
            evaluate.heading_errors_deg(roots[0], pred)[1:],
            evaluate.heading_errors_deg(roots[1], pred)[1:])))
    if args.jumps > 0:
        report = json.loads(args.job.with_suffix(".report.json").read_text())
        searched = [f.get("searched", []) for f in report["frames"]]
        print(f"a limb's error rising over {args.jumps:g} degrees in one frame:")
        for f, label, before, after, by in jumps(limbs, vs_truth, searched, args.jumps):
            print(f"  frame {f}: {label} {before:.0f} -> {after:.0f}, moved by the {by}")
    if args.one_step:
        steps = one_step_poses(job, best, at_truth=args.one_step == "at-truth")
        n = len(steps[0])
        # the tracked frames: frame 0 is the best fit's own
        beyond = evaluate.heading_errors_deg(steps[0][1:, 0], best[0][1:n, 0])
        turn = evaluate.heading_errors_deg(best[0][1:n, 0], best[0][:n - 1, 0])
        per = evaluate.limb_errors_deg(job.skeleton, steps, (best[0][:n], best[1][:n]), limbs)
        print(f"one step from the best fit ({args.one_step}): per frame, the root's heading "
              "beyond the best fit's / the best fit's turn since the frame before, degrees")
        print("  ".join(f"{a:+.1f}/{b:+.1f}" for a, b in zip(beyond, turn)))
        means = {label: per[label][1:].mean() for label, _, _ in limbs}
        print(f"  each frame's turn left undone: {lag_share(beyond, turn):.2f}; "
              "the eight limbs against the best fit: "
              f"{np.mean(list(means.values())):.2f} degrees")
        print("  each limb against the best fit: " + ", ".join(
            f"{label} {mean:.1f}" for label, mean in means.items()))
    for joint in filter(None, args.twist.split(",")):
        rows = twist_rows(job, est, best, joint)
        print(f"{joint} against the best fit, per frame: swing / twist, degrees")
        print("  ".join(f"{s:.0f}/{t:.0f}" for s, t in rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
