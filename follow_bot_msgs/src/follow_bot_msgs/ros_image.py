"""numpy <-> sensor_msgs/Image without cv_bridge (its Python module is built for Debian's numpy),
and sensor_msgs/CameraInfo from its fields."""

import numpy as np
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

IDENTITY_3X3 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]


# The arguments are the message's own field names, K, D, R and P included.
def camera_info_msg(
    width: int,
    height: int,
    K,  # noqa: N803
    D=(0.0,) * 5,  # noqa: N803
    R=IDENTITY_3X3,  # noqa: N803
    P=None,  # noqa: N803
    distortion_model: str = "plumb_bob",
    frame_id: str = "",
) -> CameraInfo:
    """A CameraInfo of these fields (row-major lists); P defaults to K with a zero fourth column
    (a monocular camera)."""
    msg = CameraInfo()
    msg.header.frame_id = frame_id
    msg.width, msg.height = width, height
    msg.distortion_model = distortion_model
    msg.K, msg.D, msg.R = list(K), list(D), list(R)
    msg.P = list(P) if P is not None else [*K[0:3], 0.0, *K[3:6], 0.0, *K[6:9], 0.0]
    return msg


def bgr_to_msg(image: np.ndarray, stamp, frame_id: str) -> Image:
    """Packs an HxWx3 uint8 BGR array into a bgr8 Image message."""
    msg = Image()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.height, msg.width = image.shape[:2]
    msg.encoding = "bgr8"
    msg.step = msg.width * 3
    msg.data = np.ascontiguousarray(image, dtype=np.uint8).tobytes()
    return msg


def bgr_to_jpeg_msg(image: np.ndarray, stamp, frame_id: str, quality: int) -> CompressedImage:
    """Codes an HxWx3 uint8 BGR array as the `compressed` image_transport publishes it."""
    import cv2  # here: the lab nodes import this module under Debian's python3, which has no cv2

    ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise ValueError(f"JPEG coding of a {image.shape} image failed")
    msg = CompressedImage()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.format = "bgr8; jpeg compressed bgr8"
    msg.data = data.tobytes()
    return msg


def msg_to_bgr(msg: Image) -> np.ndarray:
    """Unpacks a bgr8 Image message (any row padding) into an HxWx3 uint8 array."""
    if msg.encoding != "bgr8":
        raise ValueError(f"expected a bgr8 image, got {msg.encoding!r}")
    rows = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    return rows[:, : msg.width * 3].reshape(msg.height, msg.width, 3)
