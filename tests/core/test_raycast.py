"""Ray casting against brute-force sampling along each pixel's ray."""

import numpy as np

from core import raycast, se3
from core.skeleton import human_template
from support.synthetic import side_view


def _posed(seed=3):
    sk = human_template()
    rng = np.random.default_rng(seed)
    R = np.array([se3.exp_so3(rng.normal(0, 0.4, 3)) for _ in range(sk.n_joints)])
    g = sk.segment_motions(sk.joint_frames(R, sk.rest_positions[0]))
    return sk, g


def _inside(sk, g, X):
    """Boolean (N, E): is each world point inside each blob."""
    A, C = raycast.blob_frames(sk.blobs, g)
    y = np.einsum("eab,neb->nea", A, X[:, None, :] - C[None])
    return np.sum(y * y, -1) <= 1


def test_depths_match_brute_force_marching():
    sk, g = _posed()
    view = side_view(yaw_deg=35)
    rng = np.random.default_rng(0)
    pix = rng.uniform([100, 30], [220, 330], size=(400, 2))
    hits = raycast.cast(view, pix, sk.blobs, g)
    assert (hits.label >= 0).sum() > 40
    origin, d = view.ray(pix)
    lam = np.linspace(0, 10, 10001)  # 1 mm steps from the camera plane through the body
    for i in np.flatnonzero(hits.label >= 0)[:40]:
        X = origin[i] + lam[:, None] * d
        inside = _inside(sk, g, X)
        first = int(np.argmax(inside.any(1)))
        assert abs(lam[first] - hits.depth[i]) < 1.5e-3
        assert inside[first, hits.label[i]]  # the nearest surface belongs to the reported blob
    for i in np.flatnonzero(hits.label < 0)[:40]:
        X = origin[i] + lam[:, None] * d
        assert not _inside(sk, g, X).any()


def test_rasterised_labels_equal_per_pixel_casting():
    sk, g = _posed(5)
    view = side_view(yaw_deg=70)
    for step in (1, 3):
        pix, hits, box = raycast.render_labels(view, sk.blobs, g, (360, 320), step)
        ref = raycast.cast(view, pix, sk.blobs, g)
        np.testing.assert_array_equal(hits.label, ref.label)
        np.testing.assert_allclose(hits.depth, ref.depth, atol=1e-9)
        np.testing.assert_allclose(hits.world, ref.world, atol=1e-9)
        np.testing.assert_allclose(hits.rim, ref.rim, atol=1e-9)
        x0, y0, x1, y1 = box
        assert np.all(pix % step == 0)  # the grid is the multiples of step
        xs, ys = np.meshgrid(np.arange(x0 - x0 % step, x1, step),
                             np.arange(y0 - y0 % step, y1, step))
        every = raycast.cast(view, np.stack([xs.ravel(), ys.ravel()], 1).astype(float),
                             sk.blobs, g)
        assert (every.label >= 0).sum() == len(pix)  # no covered pixel of the box is missed


def test_hit_points_lie_on_their_blob_surface():
    sk, g = _posed(7)
    view = side_view(yaw_deg=10)
    pix, hits, _ = raycast.render_labels(view, sk.blobs, g, (360, 320))
    A, C = raycast.blob_frames(sk.blobs, g)
    y = np.einsum("nab,nb->na", A[hits.label], hits.world - C[hits.label])
    np.testing.assert_allclose(np.linalg.norm(y, axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(view.project(hits.world), pix, atol=1e-9)
