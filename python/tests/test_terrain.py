"""The package as its users meet it: installed into a fresh virtual environment by
`cargo test --release` (tests/python.rs), rendering the repository's bundled sketches."""

import pathlib

import numpy as np
import pytest

import terrain

ROOT = pathlib.Path(__file__).resolve().parents[2]
JACKSBORO = ROOT / "sketches" / "jacksboro.toml"
# A GeoTIFF GDAL wrote (UTM zone 16N, metres): a sketch this project did not make.
GEOTIFF = ROOT / "tests" / "data" / "formats" / "utm-metres-Float32.tif"
SIZE = 64


@pytest.fixture(scope="module")
def renderer():
    return terrain.Renderer(terrain.Scene.load(JACKSBORO), size=SIZE)


def test_outputs_have_their_shapes_and_dtypes(renderer):
    out = renderer.render(outputs=["rgb", "depth", "distance", "positions", "normals", "surface"])
    assert out["rgb"].shape == (SIZE, SIZE, 3) and out["rgb"].dtype == np.uint8
    for name in ("depth", "distance"):
        assert out[name].shape == (SIZE, SIZE) and out[name].dtype == np.float32
    assert out["positions"].shape == (SIZE, SIZE, 4) and out["positions"].dtype == np.float64
    assert out["normals"].shape == (SIZE, SIZE, 3) and out["normals"].dtype == np.float32
    assert out["K"].shape == (3, 3) and out["world_to_camera"].shape == (4, 4)
    ground = out["positions"][..., 3] > 0.5
    # The bundled view shows ground and sky; sky is infinitely far, ground is not.
    assert 0 < ground.sum() < SIZE * SIZE
    assert np.all(np.isinf(out["depth"][~ground])) and np.all(np.isfinite(out["depth"][ground]))
    lengths = np.linalg.norm(out["normals"][ground], axis=-1)
    assert np.allclose(lengths, 1.0, atol=1e-5)
    # Normals face up, toward the sky the ground is lit from.
    assert np.all(out["normals"][ground][:, 2] > 0)
    # The picture is not blank.
    assert out["rgb"].std() > 5
    # Surface classes: the sky's (0) exactly on sky, the land's elsewhere.
    assert out["surface"].shape == (SIZE, SIZE) and out["surface"].dtype == np.uint8
    assert np.array_equal(out["surface"] == 0, ~ground)
    assert terrain.SURFACE_CLASSES[0] == "sky"
    land = {terrain.SURFACE_CLASSES[c] for c in np.unique(out["surface"][ground])}
    assert land and "sky" not in land


def test_depth_is_the_distance_along_the_axis_to_the_positions(renderer):
    out = renderer.render(outputs=["depth", "distance", "positions"])
    ground = out["positions"][..., 3] > 0.5
    points = out["positions"][..., :3][ground]
    c2w = out["camera_to_world"]
    eye, forward = c2w[:3, 3], c2w[:3, 2]
    along = (points - eye) @ forward
    depth = out["depth"][ground].astype(np.float64)
    assert np.max(np.abs(depth - along) / along) < 1e-4
    ray = np.linalg.norm(points - eye, axis=-1)
    assert np.max(np.abs(out["distance"][ground] - ray) / ray) < 1e-4
    # Projected with K and the extrinsics, each point lands on its pixel's centre.
    w2c = out["world_to_camera"]
    cam = points @ w2c[:3, :3].T + w2c[:3, 3]
    uv = cam @ out["K"].T
    uv = uv[:, :2] / uv[:, 2:]
    rows, cols = np.nonzero(ground)
    assert np.max(np.hypot(uv[:, 0] - cols, uv[:, 1] - rows)) < 0.01


def test_a_hundred_renders_reuse_one_device():
    before = terrain.devices_opened()
    r = terrain.Renderer(terrain.Scene.load(JACKSBORO), size=16)
    cameras = terrain.random_cameras(terrain.Scene.load(JACKSBORO), 100, seed=3)
    for c in cameras:
        assert r.render(camera=c)["rgb"].shape == (16, 16, 3)
    assert terrain.devices_opened() - before == 1


def test_random_cameras_are_a_function_of_the_seed_and_stand_above_ground(renderer):
    scene = terrain.Scene.load(JACKSBORO)
    a = terrain.random_cameras(scene, 5, seed=7)
    b = terrain.random_cameras(scene, 5, seed=7)
    c = terrain.random_cameras(scene, 5, seed=8)
    assert [x.position for x in a] == [x.position for x in b]
    assert [x.position for x in a] != [x.position for x in c]
    for cam in a:
        x, y, z = cam.position
        assert z > renderer.height_at(x, y)


def test_cameras_by_place_on_a_georeferenced_sketch():
    scene = terrain.Scene.from_sketch(GEOTIFF)
    r = terrain.Renderer(scene, size=(48, 32))
    cam = terrain.Camera(lat_deg=36.625, lon_deg=-84.232, altitude_m=800.0, heading_deg=0.0,
                         pitch_deg=-40.0)
    out = r.render(camera=cam, outputs=["rgb", "latlon"])
    assert out["rgb"].shape == (32, 48, 3)
    latlon = out["latlon"]
    seen = np.isfinite(latlon[..., 0])
    assert seen.any()
    # Looking north from 36.625° N: the ground seen lies north of the camera, near it.
    assert np.all(latlon[seen][:, 0] > 36.625)
    assert np.all(np.abs(latlon[seen][:, 1] + 84.232) < 0.1)


def test_a_bad_scene_raises_terrain_error_with_one_line(tmp_path):
    with pytest.raises(terrain.Error) as e:
        terrain.Scene.load(tmp_path / "missing.toml")
    assert "missing.toml" in str(e.value) and "\n" not in str(e.value)
    bad = tmp_path / "bad.toml"
    bad.write_text('[detail]\noctaves = "many"\n')
    with pytest.raises(terrain.Error) as e:
        terrain.Scene.load(bad)
    assert "detail.octaves" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(terrain.Error, match="mode"):
        terrain.Renderer(terrain.Scene.load(JACKSBORO), size=16, mode="fastest")
    with pytest.raises(terrain.Error, match="size"):
        terrain.Renderer(terrain.Scene.load(JACKSBORO), size=0)


def test_bad_cameras_and_outputs_raise_terrain_error(renderer, tmp_path):
    with pytest.raises(terrain.Error, match="camera"):
        renderer.render(camera=terrain.Camera(position=(0.0, 0.0, float("nan")), look_at=(1, 1, 0)))
    with pytest.raises(terrain.Error, match="output"):
        renderer.render(outputs=["rgb", "albedo"])
    synthetic = tmp_path / "hills.toml"
    synthetic.write_text('[sketch]\nsynthetic = "hills"\nsize = 65\n')
    plain = terrain.Renderer(terrain.Scene.load(synthetic), size=16)
    with pytest.raises(terrain.Error, match="latlon"):
        plain.render(outputs=["latlon"])  # a synthetic sketch has no georeference
