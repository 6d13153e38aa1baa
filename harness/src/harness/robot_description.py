"""`rosrun harness robot_description --world NAME [--robot PRESET]`: the URDF of a harness world's
camera mounting, or of the robot preset's camera the simulator plays on that world (follow_bot's
generator, follow_bot/python/follow_bot/robot_description.py), so that tf and the rendered frames
agree. Without --world it is follow_bot's: a robot preset and mounting flags.

    rosrun harness robot_description --world course
"""

from __future__ import annotations

import math
import sys

from follow_bot.robot_description import BASE_LINK_HEIGHT, mounting, mounting_parser, urdf
from harness.robot_preset import robot_world
from harness.world import WorldError
from harness.world_file import load_world, resolve_world_path

__all__ = ["BASE_LINK_HEIGHT", "main", "urdf"]


def main(argv: list[str] | None = None) -> int:
    parser = mounting_parser("Prints the robot's URDF (a base with one camera).")
    parser.add_argument("--world", help="take the mounting from this world's camera (a name in "
                        "worlds/ or a YAML path) instead of the preset and the flags")  # fmt: skip
    args = parser.parse_args(argv)
    try:
        if args.world:
            world = load_world(resolve_world_path(args.world))
            camera = (robot_world(world, args.robot) if args.robot else world).camera
            text = urdf(camera.height_m, math.degrees(camera.pitch), camera.x_offset_m,
                        camera.frame_id)  # fmt: skip
        else:
            text = urdf(**mounting(args))
        sys.stdout.write(text)
    except (ValueError, WorldError) as error:
        parser.error(str(error))
    return 0


if __name__ == "__main__":
    sys.exit(main())
