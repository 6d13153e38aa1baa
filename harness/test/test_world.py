"""World loading: shipped worlds are what they claim, malformed files name the bad field."""

import copy
import math

import cv2
import numpy as np
import pytest

from harness.geometry import polyline_length
from harness.ground import ground_texture
from harness.world import AprilTagMarker, Box, Sphere, WorldError
from harness.world_file import load_world, parse_world

MINIMAL = {
    "name": "t",
    "ground": {"size": [4.0, 4.0]},
    "objects": [
        {"kind": "sphere", "colour": [0, 0, 255], "radius": 0.2, "position": [1, 0, 0.2]},
        {"kind": "box", "colour": [0, 90, 0], "size": [1, 1, 1], "pose": [2, 0, 0]},
        {"kind": "sphere", "colour": [0, 255, 0], "radius": 0.1, "position": [1, 1, 0.1]},
    ],
}


def test_minimal_world_defaults():
    w = parse_world(MINIMAL)
    assert w.ground.origin == (-2.0, -2.0)
    assert w.ground.metres_per_pixel == 0.005
    assert w.camera.width == 640 and w.camera.hfov == pytest.approx(math.radians(60))
    assert w.noise.sigma == 0.0 and w.lighting.gain == 1.0
    assert w.robot.max_v == 0.7 and w.robot.max_w == pytest.approx(math.pi)
    assert [o.name for o in w.objects] == ["sphere0", "box1", "sphere2"]
    assert np.linalg.norm(w.lighting.direction) == pytest.approx(1.0)
    assert (w.camera_transport.name, w.camera_transport.jpeg_quality) == ("raw", 80)


def test_camera_transport_fields_sit_beside_the_mounting():
    data = copy.deepcopy(MINIMAL)
    data["camera"] = {"pitch_deg": 20, "transport": "compressed", "jpeg_quality": 60}
    w = parse_world(data)
    assert (w.camera_transport.name, w.camera_transport.jpeg_quality) == ("compressed", 60)
    assert w.camera.pitch == pytest.approx(math.radians(20))


def test_course_loop(worlds):
    w = worlds["course"]
    line = w.ground.lines[0]
    assert line.closed and line.colour == (0, 220, 255) and line.width == pytest.approx(0.05)
    c = w.centreline()
    length = polyline_length(c, closed=True)
    assert length >= 15.0
    # Densely sampled (<= 1 cm) and inside the floor with margin.
    steps = np.hypot(*np.diff(np.vstack([c, c[:1]]), axis=0).T)
    assert steps.max() <= 0.0100001
    assert np.all(np.abs(c) < 4.9)
    # Curvature from consecutive headings: tightest radius 0.6 m, both turn directions (S-bend).
    heading = np.unwrap(np.arctan2(*np.diff(np.vstack([c, c[:1]]), axis=0).T[::-1]))
    curvature = np.diff(heading) / steps[1:]
    assert 1.0 / np.abs(curvature).max() == pytest.approx(0.6, rel=0.02)
    assert curvature.min() < -1.0 and curvature.max() > 1.0
    assert heading[-1] - heading[0] == pytest.approx(2 * math.pi, abs=0.02)  # one CCW loop


def test_centreline_is_painted_in_the_texture(worlds):
    w = worlds["course"]
    tex, tex_to_world = ground_texture(w)
    px = (
        np.column_stack([w.centreline(), np.ones(len(w.centreline()))])
        @ np.linalg.inv(tex_to_world).T
    )
    cols, rows = np.rint(px[:, 0]).astype(int), np.rint(px[:, 1]).astype(int)
    np.testing.assert_array_equal(tex[rows, cols], np.tile([0, 220, 255], (len(rows), 1)))
    # 5 cm = 10 px wide: 6 px beside the first straight (along x) is plain floor again.
    assert (tex[rows[:100] + 6, cols[:100]] == w.ground.colour).all()


def test_floors_are_not_target_colours(worlds):
    for w in worlds.values():
        b, g, r = w.ground.colour
        assert max(b, g, r) - min(b, g, r) < 30, w.name  # grey-ish


def test_shipped_objects(worlds):
    rgb = worlds["rgb"].objects
    assert [o.name for o in rgb] == ["red", "green", "blue"]
    assert all(isinstance(o, Sphere) and o.position[2] == o.radius for o in rgb)
    assert [np.argmax(o.colour) for o in rgb] == [2, 1, 0]  # BGR: red, green, blue
    (box,) = worlds["dumpster"].objects
    assert isinstance(box, Box) and sorted(box.size) == [1.0, 1.2, 1.8]
    (tag,) = worlds["parking"].objects
    assert isinstance(tag, AprilTagMarker)
    assert (tag.family, tag.tag_id, tag.size, tag.post) == ("tag36h11", 0, 0.30, True)
    sx, sy, _ = worlds["parking"].robot.start
    normal = np.array([math.cos(tag.pose[3]), math.sin(tag.pose[3])])
    to_robot = np.array([sx - tag.pose[0], sy - tag.pose[1]])
    assert normal @ to_robot / np.linalg.norm(to_robot) > 0.99  # faces the robot start


def _broken(path, value):
    """MINIMAL with the field at `path` (list of keys) replaced, or deleted if value is None."""
    data = copy.deepcopy(MINIMAL)
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is None:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (["ground"], None, r"^ground: missing required field"),
        (["objects", 2, "radius"], -1, r"^objects\[2\]\.radius: must be > 0, got -1"),
        (["objects", 0, "radius"], "big", r"^objects\[0\]\.radius: must be a number, got str"),
        (["objects", 0, "radius"], True, r"^objects\[0\]\.radius: must be a number, got bool"),
        (
            ["objects", 1, "kind"],
            "cylinder",
            r"^objects\[1\]\.kind: unknown object kind 'cylinder'",
        ),
        (["objects", 1, "size"], [1, 1], r"^objects\[1\]\.size: must have 3 entries, got 2"),
        (["objects", 0, "colour"], [0, 0, 300], r"^objects\[0\]\.colour\[2\]: must be an integer"),
        (["objects", 0, "color"], [0, 0, 1], r"^objects\[0\]\.color: unknown field"),
        (["objects", 0, "position"], None, r"^objects\[0\]\.position: missing required field"),
        (["ground", "size"], "4x4", r"^ground\.size: must be a list, got str"),
        (["ground", "metres_per_pixel"], 1e-5, r"^ground\.metres_per_pixel: .* limit is 8000"),
        (["camera"], {"pitch_deg": 95}, r"^camera\.pitch_deg: must be < 89"),
        (["camera"], {"transport": "theora"}, r"^camera\.transport: must be one of raw, compr"),
        (["camera"], {"jpeg_quality": 101}, r"^camera\.jpeg_quality: must be at most 100, got"),
        (["camera"], {"jpeg_quality": 0}, r"^camera\.jpeg_quality: must be >= 1"),
        (["noise"], {"seed": 1.5}, r"^noise\.seed: must be an integer"),
        (["lighting"], {"direction": [0, 0, -1]}, r"^lighting\.direction\[2\]: light must come"),
        (["objects"], {"a": 1}, r"^objects: must be a list"),
        (["name"], None, r"^name: missing required field"),
    ],
)
def test_malformed_world_names_the_field(path, value, message):
    with pytest.raises(WorldError, match=message):
        parse_world(_broken(path, value))


@pytest.mark.parametrize(
    ("obj", "message"),
    [
        ({"kind": "apriltag", "id": 587, "size": 0.1, "pose": [0, 0, 1, 0]}, r"\.id: tag36h11"),
        ({"kind": "apriltag", "id": 1, "size": 0.1, "pose": [0, 0, 0.01, 0]}, r"below the floor"),
        (
            {"kind": "apriltag", "family": "tag16h5", "id": 1, "size": 0.1, "pose": [0, 0, 1, 0]},
            r"\.family: unsupported family",
        ),
        (
            {"kind": "texture", "image": "nope.png", "width": 1.0, "pose": [0, 0, 1, 0]},
            r"\.image: cannot read image file",
        ),
        (
            {
                "name": "sphere0",
                "kind": "sphere",
                "colour": [1, 2, 3],
                "radius": 1,
                "position": [0, 0, 1],
            },
            r"duplicate object name",
        ),
        ({"colour": [1, 2, 3]}, r"^objects\[3\]\.kind: missing required field"),
    ],
)
def test_malformed_objects(obj, message):
    data = copy.deepcopy(MINIMAL)
    data["objects"].append(obj)
    with pytest.raises(WorldError, match=message):
        parse_world(data)


def test_lines_validation():
    square = {"points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": True}
    w = parse_world(_broken(["ground", "lines"], [square]))
    assert polyline_length(w.centreline(), closed=True) == pytest.approx(4.0)
    open_arc = {"start": [0, 0, 0], "segments": [{"radius": 1.0, "turn_deg": 90}]}
    pts = parse_world(_broken(["ground", "lines"], [open_arc])).centreline()
    np.testing.assert_allclose(pts[-1], [1.0, 1.0], atol=1e-12)
    not_closed = {**open_arc, "closed": True}
    with pytest.raises(
        WorldError, match=r"^ground\.lines\[0\]\.segments: closed path ends 1\.414 m"
    ):
        parse_world(_broken(["ground", "lines"], [not_closed]))
    both = {**square, "start": [0, 0, 0], "segments": [{"straight": 1}]}
    with pytest.raises(WorldError, match=r"^ground\.lines\[0\]: give exactly one of"):
        parse_world(_broken(["ground", "lines"], [both]))
    bad_seg = {"start": [0, 0, 0], "segments": [{"straight": 1, "radius": 2}]}
    with pytest.raises(WorldError, match=r"^ground\.lines\[0\]\.segments\[0\]: give either"):
        parse_world(_broken(["ground", "lines"], [bad_seg]))
    with pytest.raises(WorldError, match=r"^ground\.lines\[0\]: world 't' has 0 lines"):
        parse_world(MINIMAL).centreline()


def test_files(tmp_path):
    bad_yaml = tmp_path / "bad.yaml"
    bad_yaml.write_text("name: [unclosed\n")
    with pytest.raises(WorldError, match="invalid YAML"):
        load_world(bad_yaml)
    with pytest.raises(WorldError, match="cannot read world file"):
        load_world(tmp_path / "missing.yaml")
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    with pytest.raises(WorldError, match="^world: must be a mapping, got null"):
        load_world(empty)
    # Image paths resolve relative to the world file.
    cv2.imwrite(str(tmp_path / "pic.png"), np.zeros((20, 40, 3), np.uint8))
    world = tmp_path / "w.yaml"
    world.write_text(
        "name: w\nground: {size: [2, 2], texture: {image: pic.png, metres_per_pixel: 0.01}}\n"
        "objects: [{kind: texture, image: pic.png, width: 0.4, pose: [1, 0, 0.5, 3.14]}]\n"
    )
    w = load_world(world)
    assert w.objects[0].board_size == pytest.approx((0.4, 0.2))
    assert w.ground.texture.origin == (-1.0, -1.0)
