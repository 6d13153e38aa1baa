"""A robot preset (follow_bot/config/robots.yaml, read by follow_bot.robot_description) played
by the simulator: the preset's camera (size, lens, mounting, frame, transport, topics) and its
base's speed limits replace the world's, so a scenario drives the robot the launch files set up
for `robot:=NAME`. Without a robot (or generic) follow_bot is not imported: an installed harness
plays worlds' own cameras without it."""

from __future__ import annotations

import math
from dataclasses import replace

from harness.world import CameraTransport, World

# The preset that fixes no camera in the simulator: a world's own camera plays it, on the topics
# the behaviours subscribe to by their own names.
GENERIC = "generic"
OWN_TOPICS = ("camera/rgb/image_raw", "camera/rgb/camera_info")


def preset(name: str) -> dict:
    """The robot preset `name`; ValueError naming the presets when there is none."""
    from follow_bot.robot_description import preset as follow_bot_preset

    return follow_bot_preset(name)


def robot_world(world: World, name: str) -> World:
    """`world` with the robot preset `name`'s camera and base limits (a preset without limits
    keeps the world robot's); generic: `world` as it is."""
    if name == GENERIC:
        return world
    p = preset(name)
    camera = replace(
        world.camera, width=p["width"], height=p["height"], hfov=math.radians(p["hfov_deg"]),
        height_m=p["camera_height"], pitch=math.radians(p["camera_pitch_deg"]),
        x_offset_m=p["camera_x_offset"], frame_id=p["camera_frame"],
    )  # fmt: skip
    limits = p.get("limits", {})
    robot = replace(
        world.robot, max_v=limits.get("limit_linear", world.robot.max_v),
        max_w=limits.get("limit_angular", world.robot.max_w),
    )  # fmt: skip
    transport = CameraTransport(p["image_transport"], world.camera_transport.jpeg_quality)
    return replace(world, camera=camera, robot=robot, camera_transport=transport)


def camera_topics(name: str | None) -> tuple[str, str]:
    """The image (image_transport base) and camera_info topics of robot `name` (None or generic:
    the behaviours' own names)."""
    if name in (None, GENERIC):
        return OWN_TOPICS
    p = preset(name)
    return p["image"], p["camera_info"]


def frame_rate(name: str) -> float | None:
    """The rate the robot's camera launch sets, Hz (None: the preset says none)."""
    rate = preset(name).get("frame_rate")
    return None if rate is None else float(rate)
