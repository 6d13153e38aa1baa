"""Records a behaviour's `~markers` (visualization_msgs/MarkerArray) during a run, for
run_scenario --markers: `python3 -m harness.marker_record _out:=markers.json`.

Subscribes to the one MarkerArray topic published in its namespace (waits for it) and, when
stopped, writes every message received as JSON: a list of frames, each {"t": the simulator's
step time of the camera frame (its stamp less the clock's pre-roll, record.npz's `t`), "frame":
the markers' frame, "markers": the markers it added, each {"ns", "id", "type" (the Marker
constant's name, e.g. SPHERE, ARROW, LINE_STRIP), "position", "points", "scale", "colour",
"text"}}. Every message opens with a DELETEALL, so a frame is all the behaviour shows.
"""

from __future__ import annotations

import json
from pathlib import Path

import genpy.dynamic
import rospy

from harness.sim_node import CLOCK_PREROLL_S, find_topic

TOPIC_TYPE = "visualization_msgs/MarkerArray"
TOPIC_WAIT_S = 60.0  # wall s for the behaviour to advertise its markers
SHAPES = ("ARROW", "SPHERE", "LINE_STRIP", "SPHERE_LIST", "TEXT_VIEW_FACING")  # those it draws


class MarkerDecoder:
    """MarkerArray messages as dicts. Debian ships no Python visualization_msgs, so the classes
    are generated from the definition the publisher sends with its connection (as rosbag does)."""

    def __init__(self):
        self.array_class = None
        self.shape_names: dict[int, str] = {}
        self.add = None

    def frame(self, raw: rospy.AnyMsg) -> dict:
        if self.array_class is None:
            header = raw._connection_header
            classes = genpy.dynamic.generate_dynamic(TOPIC_TYPE, header["message_definition"])
            self.array_class = classes[TOPIC_TYPE]
            marker = classes["visualization_msgs/Marker"]
            self.shape_names = {getattr(marker, name): name for name in SHAPES}
            self.add = marker.ADD
        array = self.array_class().deserialize(raw._buff)
        header = array.markers[0].header  # the DELETEALL's: the frame's stamp and base frame
        return {
            "t": round(header.stamp.to_sec() - CLOCK_PREROLL_S, 6),
            "frame": header.frame_id,
            "markers": [self.marker(m) for m in array.markers if m.action == self.add],
        }

    def marker(self, marker) -> dict:
        return {
            "ns": marker.ns,
            "id": marker.id,
            "type": self.shape_names.get(marker.type, str(marker.type)),
            "position": [marker.pose.position.x, marker.pose.position.y, marker.pose.position.z],
            "points": [[p.x, p.y, p.z] for p in marker.points],
            "scale": [marker.scale.x, marker.scale.y, marker.scale.z],
            "colour": [marker.color.r, marker.color.g, marker.color.b, marker.color.a],
            "text": marker.text,
        }


def main() -> None:
    rospy.init_node("marker_record")
    out = Path(rospy.get_param("~out"))
    frames: list[dict] = []
    rospy.on_shutdown(lambda: out.write_text(json.dumps(frames)))
    decoder = MarkerDecoder()
    topic = find_topic(TOPIC_TYPE, TOPIC_WAIT_S)
    if not topic:
        raise ValueError(f"no {TOPIC_TYPE} topic within {TOPIC_WAIT_S:g} s")
    rospy.Subscriber(topic, rospy.AnyMsg, lambda raw: frames.append(decoder.frame(raw)),
                     queue_size=100)  # fmt: skip
    rospy.spin()


if __name__ == "__main__":
    main()
