"""The command line of the harness's rospy nodes: --help describes the node, starting nothing (it
is parsed before rospy.init_node, which would wait for a master); anything but ROS remappings and
_param:= is a usage error (exit 2). Exit codes of the nodes' own are here too."""

import argparse

# The simulator's exit code when it ended a lockstep run because the behaviour under test is not
# running (sim_node); run_scenario reports such a run as could not run.
BEHAVIOUR_GONE = 3


def parse_node_command_line(argv: list[str], prog: str, description: str, epilog: str = "") -> None:
    """`argv`: rospy.myargv()[1:], the command line without the ROS arguments."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description=description,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=epilog or None,
    )
    parser.parse_args(argv)
