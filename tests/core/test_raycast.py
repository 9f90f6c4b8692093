"""Ray casting against brute-force sampling along each pixel's ray."""

import numpy as np
import pytest

from core import raycast, se3
from core.skeleton import human_template
from support.synthetic import side_pinhole, side_view

CAMERAS = pytest.mark.parametrize("camera", [side_view, side_pinhole],
                                  ids=["orthographic", "pinhole"])


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


@CAMERAS
def test_depths_match_brute_force_marching(camera):
    sk, g = _posed()
    view = camera(yaw_deg=35)
    rng = np.random.default_rng(0)
    pix = rng.uniform([100, 30], [220, 330], size=(400, 2))
    hits = raycast.cast(view, pix, sk.blobs, g)
    assert (hits.label >= 0).sum() > 40
    origin, d = view.ray(pix)
    lam = np.linspace(0, 10, 10001)  # 1 mm steps from the camera (plane) through the body
    for i in np.flatnonzero(hits.label >= 0)[:40]:
        X = origin[i] + lam[:, None] * d[i]
        inside = _inside(sk, g, X)
        first = int(np.argmax(inside.any(1)))
        assert abs(lam[first] - hits.depth[i]) < 1.5e-3
        assert inside[first, hits.label[i]]  # the nearest surface belongs to the reported blob
    for i in np.flatnonzero(hits.label < 0)[:40]:
        X = origin[i] + lam[:, None] * d[i]
        assert not _inside(sk, g, X).any()


@CAMERAS
def test_rasterised_labels_equal_per_pixel_casting(camera):
    sk, g = _posed(5)
    view = camera(yaw_deg=70)
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


@CAMERAS
def test_a_label_grids_image_map_and_its_hits_there_match_casting_every_pixel(camera):
    """``LabelGrid.full`` labels every step-th pixel of the image as casting that pixel does,
    and ``hits_on_full`` at a map pixel is that pixel's cast hit."""
    sk, g = _posed(4)
    view = camera(yaw_deg=30)
    shape = (350, 310)
    for step in (1, 2, 3):
        grid = raycast.label_grid(view, sk.blobs, g, shape, step)
        full = grid.full(shape)
        assert full.shape == (-(-350 // step), -(-310 // step))
        ys, xs = np.mgrid[0:full.shape[0], 0:full.shape[1]]
        pix = np.stack([xs.ravel(), ys.ravel()], 1) * step
        ref = raycast.cast(view, pix.astype(float), sk.blobs, g)
        np.testing.assert_array_equal(full.ravel(), ref.label)
        rows, cols = np.nonzero(full >= 0)
        pick = np.random.default_rng(step).choice(len(rows), 50, replace=False)
        hits = grid.hits_on_full(rows[pick], cols[pick])
        at = rows[pick] * full.shape[1] + cols[pick]
        np.testing.assert_array_equal(hits.label, ref.label[at])
        np.testing.assert_allclose(hits.world, ref.world[at], atol=1e-9)
        np.testing.assert_allclose(hits.rim, ref.rim[at], atol=1e-9)


@CAMERAS
def test_a_windows_labels_are_the_full_maps_there_and_none_beyond(camera):
    """``LabelGrid.window`` reads ``full``'s map on any window of its cells, one reaching
    past the map's edges included (-1 there)."""
    sk, g = _posed(4)
    shape = (350, 310)
    grid = raycast.label_grid(camera(yaw_deg=30), sk.blobs, g, shape, 2)
    full = grid.full(shape)
    padded = np.pad(full, 60, constant_values=-1)
    for x0, y0, h, w in ((0, 0, 175, 155), (30, 50, 60, 40), (-20, -10, 90, 200),
                         (140, 160, 40, 40), (200, 10, 5, 5)):
        np.testing.assert_array_equal(grid.window(x0, y0, (h, w)),
                                      padded[y0 + 60:y0 + 60 + h, x0 + 60:x0 + 60 + w])


@CAMERAS
def test_outline_areas_are_the_pixels_each_blob_alone_covers(camera):
    """``outline_areas`` (pi / sqrt(det P)) against counting the pixels each blob, cast on
    its own, covers: equal within the pixel grid's error along the outline."""
    sk, g = _posed(5)
    view = camera(yaw_deg=40)
    areas = raycast.outline_areas(view, sk.blobs, g)
    for e, blob in enumerate(sk.blobs):
        pix, _, _ = raycast.render_labels(view, [blob], g, (360, 320))
        if areas[e] > 150:  # well inside the image (the arms and legs may leave it)
            assert len(pix) == pytest.approx(areas[e], rel=0.08), blob.name


@CAMERAS
def test_hit_points_lie_on_their_blob_surface(camera):
    sk, g = _posed(7)
    view = camera(yaw_deg=10)
    pix, hits, _ = raycast.render_labels(view, sk.blobs, g, (360, 320))
    A, C = raycast.blob_frames(sk.blobs, g)
    y = np.einsum("nab,nb->na", A[hits.label], hits.world - C[hits.label])
    np.testing.assert_allclose(np.linalg.norm(y, axis=1), 1.0, atol=1e-9)
    np.testing.assert_allclose(view.project(hits.world), pix, atol=1e-9)


@CAMERAS
def test_outline_ellipses_bound_the_cast_pixels(camera):
    """A pixel is inside a blob's outline (``Camera.ellipses``) exactly where its ray meets
    that blob, and the blob boxes hold every such pixel."""
    sk, g = _posed(9)
    view = camera(yaw_deg=50)
    A, C = raycast.blob_frames(sk.blobs, g)
    c, P = view.ellipses(A, C)
    boxes = raycast.blob_boxes(view, sk.blobs, g)
    rng = np.random.default_rng(2)
    pix = rng.uniform([60, 0], [260, 360], size=(3000, 2))
    origin, d = view.ray(pix)
    for e in range(len(sk.blobs)):  # the ray against this blob alone
        w, v = (origin - C[e]) @ A[e].T, d @ A[e].T
        b, a = np.sum(w * v, 1), np.sum(v * v, 1)
        meets = b * b - a * (np.sum(w * w, 1) - 1) > 0
        r = pix - c[e]
        inside = np.einsum("na,ab,nb->n", r, P[e], r) <= 1
        near = np.abs(np.einsum("na,ab,nb->n", r, P[e], r) - 1) < 1e-6
        assert np.all((meets == inside) | near)
        lo, hi = boxes[e, :2], boxes[e, 2:]
        assert np.all((pix[meets] >= lo - 1e-9) & (pix[meets] <= hi + 1e-9))
        # the box is tight: its edges touch the outline
        edge = np.stack([np.full(4001, lo[0]), np.linspace(lo[1], hi[1], 4001)], 1)
        assert np.min(np.einsum("na,ab,nb->n", edge - c[e], P[e], edge - c[e])) == \
            pytest.approx(1.0, abs=1e-4)


def test_a_pinhole_shows_nearer_blobs_larger():
    """Two equal blobs at different depths: through a pinhole the nearer one's outline is
    larger by the depths' ratio, under orthography they are equal."""
    from core.skeleton import Ellipsoid
    blobs = [Ellipsoid(0, f"ball{z}", np.array([0.0, 0.9, z]), np.full(3, 0.1), np.eye(3))
             for z in (0.0, 1.0)]
    g = np.eye(4)[None]
    for camera, ratio in ((side_view, 1.0), (side_pinhole, 3.0 / 2.0)):
        view = camera(yaw_deg=0)  # looking along -z: the second blob is 1 unit nearer
        boxes = raycast.blob_boxes(view, blobs, g)
        widths = boxes[:, 2] - boxes[:, 0]
        assert widths[1] / widths[0] == pytest.approx(ratio, rel=0.02)


def test_label_grids_of_several_views_are_each_views_own_label_grid():
    """One pose's views z-buffered together (an orthographic view, a pinhole, one whose
    image the body misses; sizes and steps apart) give each view what it gives alone."""
    sk, g = _posed(4)
    views = [side_view(yaw_deg=30), side_pinhole(yaw_deg=60), side_view(center=(-900, 180))]
    shapes, steps = [(350, 310), (300, 400), (350, 310)], [2, 1, 3]
    together = raycast.label_grids(views, sk.blobs, g, shapes, steps)
    assert together[2].box is None and together[0].box is not None
    for view, shape, step, grid in zip(views, shapes, steps, together):
        alone = raycast.label_grid(view, sk.blobs, g, shape, step)
        assert grid.box == alone.box and grid.step == alone.step
        np.testing.assert_array_equal(grid.label, alone.label)
        rows, cols = grid.covered()
        for a, b in zip(vars(grid.hits(rows, cols)).values(),
                        vars(alone.hits(rows, cols)).values()):
            np.testing.assert_array_equal(a, b)
