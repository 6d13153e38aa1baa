"""ctypes bindings to Debian's libapriltag: tag bitmaps for rendering, a detector for tests.

Tag bits always come from the library itself, never from hand-typed tables, so the rendered
tags are exactly what the real detector (and the robot's C++ detector) expects.
Struct layouts follow /usr/include/apriltag/{apriltag.h,apriltag_pose.h,common/*.h} (v3).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np

SONAME = "libapriltag.so.3"
# The detector puts pixel centres at (i + 0.5, j + 0.5) (see its quad_decimate rescaling);
# OpenCV and ROS CameraInfo put them at integers. Measured: a black square covering pixels
# 50..129 of a blurred synthetic image is reported centred at 90.0, not 89.5.
DETECTOR_PIXEL_OFFSET = 0.5


class _ImageU8(ctypes.Structure):
    _fields_ = (
        ("width", ctypes.c_int32),
        ("height", ctypes.c_int32),
        ("stride", ctypes.c_int32),
        ("buf", ctypes.POINTER(ctypes.c_uint8)),
    )


class _Family(ctypes.Structure):
    _fields_ = (
        ("ncodes", ctypes.c_uint32),
        ("codes", ctypes.POINTER(ctypes.c_uint64)),
        ("width_at_border", ctypes.c_int),
        ("total_width", ctypes.c_int),
        ("reversed_border", ctypes.c_bool),
        ("nbits", ctypes.c_uint32),
        ("bit_x", ctypes.POINTER(ctypes.c_uint32)),
        ("bit_y", ctypes.POINTER(ctypes.c_uint32)),
        ("h", ctypes.c_uint32),
        ("name", ctypes.c_char_p),
        ("impl", ctypes.c_void_p),
    )


class _DetectorPrefix(ctypes.Structure):
    """Leading, user-settable fields of apriltag_detector_t (never allocated from Python)."""

    _fields_ = (
        ("nthreads", ctypes.c_int),
        ("quad_decimate", ctypes.c_float),
        ("quad_sigma", ctypes.c_float),
        ("refine_edges", ctypes.c_bool),
        ("decode_sharpening", ctypes.c_double),
        ("debug", ctypes.c_bool),
    )


class _Detection(ctypes.Structure):
    _fields_ = (
        ("family", ctypes.POINTER(_Family)),
        ("id", ctypes.c_int),
        ("hamming", ctypes.c_int),
        ("decision_margin", ctypes.c_float),
        ("H", ctypes.c_void_p),
        ("c", ctypes.c_double * 2),
        ("p", (ctypes.c_double * 2) * 4),
    )


class _ZArray(ctypes.Structure):
    _fields_ = (
        ("el_sz", ctypes.c_size_t),
        ("size", ctypes.c_int),
        ("alloc", ctypes.c_int),
        ("data", ctypes.c_void_p),
    )


class _DetectionInfo(ctypes.Structure):
    _fields_ = (
        ("det", ctypes.POINTER(_Detection)),
        ("tagsize", ctypes.c_double),
        ("fx", ctypes.c_double),
        ("fy", ctypes.c_double),
        ("cx", ctypes.c_double),
        ("cy", ctypes.c_double),
    )


class _Pose(ctypes.Structure):
    _fields_ = (("R", ctypes.c_void_p), ("t", ctypes.c_void_p))


class AprilTagError(RuntimeError):
    """libapriltag is missing or was asked for something it does not have."""


@functools.cache
def _lib() -> ctypes.CDLL:
    """Load libapriltag once, on first use, so worlds without tags never need it."""
    names = [SONAME] + [n for n in [ctypes.util.find_library("apriltag")] if n]
    for name in names:
        try:
            lib = ctypes.CDLL(name)
            break
        except OSError:
            continue
    else:
        raise AprilTagError(
            f"cannot load {SONAME}; install Debian's libapriltag3 (apt-get install libapriltag-dev)"
        )
    lib.apriltag_to_image.restype = ctypes.POINTER(_ImageU8)
    lib.apriltag_to_image.argtypes = [ctypes.POINTER(_Family), ctypes.c_int]
    lib.apriltag_detector_create.restype = ctypes.POINTER(_DetectorPrefix)
    lib.apriltag_detector_add_family_bits.argtypes = [
        ctypes.POINTER(_DetectorPrefix),
        ctypes.POINTER(_Family),
        ctypes.c_int,
    ]
    lib.apriltag_detector_detect.restype = ctypes.POINTER(_ZArray)
    lib.apriltag_detector_detect.argtypes = [
        ctypes.POINTER(_DetectorPrefix),
        ctypes.POINTER(_ImageU8),
    ]
    lib.apriltag_detections_destroy.argtypes = [ctypes.POINTER(_ZArray)]
    lib.estimate_tag_pose.restype = ctypes.c_double
    lib.estimate_tag_pose.argtypes = [ctypes.POINTER(_DetectionInfo), ctypes.POINTER(_Pose)]
    return lib


@functools.cache
def _free() -> Any:
    """libc free(). Debian's libapriltag.so exports neither image_u8_destroy nor
    matd_destroy (only apriltag_* / tag* / estimate_*); both are plain free() of
    malloc'd blocks in v3 (image_u8: buffer then struct; matd: one block)."""
    free = ctypes.CDLL(None).free
    free.argtypes = [ctypes.c_void_p]
    free.restype = None
    return free


@functools.cache
def _family(name: str) -> ctypes._Pointer:
    """Create a family once; the decode tables are costly and never freed (process lifetime)."""
    lib = _lib()
    try:
        create = getattr(lib, f"{name}_create")
    except AttributeError:
        raise AprilTagError(f"libapriltag has no tag family {name!r}") from None
    create.restype = ctypes.POINTER(_Family)
    return create()


def family_geometry(family: str = "tag36h11") -> tuple[int, int, int]:
    """(ncodes, total_width, width_at_border) in tag cells, as reported by the library."""
    fam = _family(family).contents
    return fam.ncodes, fam.total_width, fam.width_at_border


def tag_image(family: str = "tag36h11", tag_id: int = 0) -> np.ndarray:
    """The library's tag bitmap (uint8, 0 black / 255 white), including its white border.

    For tag36h11 this is 10x10 cells: a 1-cell white border around the 8x8 black square.
    """
    ncodes = family_geometry(family)[0]
    if not 0 <= tag_id < ncodes:
        raise AprilTagError(f"{family} has ids 0..{ncodes - 1}, got {tag_id}")
    lib = _lib()
    img = lib.apriltag_to_image(_family(family), tag_id)
    try:
        im = img.contents
        rows = np.ctypeslib.as_array(im.buf, shape=(im.height, im.stride))
        return rows[:, : im.width].copy()
    finally:
        _free()(ctypes.cast(img.contents.buf, ctypes.c_void_p))
        _free()(ctypes.cast(img, ctypes.c_void_p))


@dataclass(frozen=True)
class Detection:
    """One detected tag, in OpenCV pixel coordinates (pixel centres at integers).

    Corners follow the library order: bottom-left, bottom-right, top-right, top-left of the
    tag as seen by the camera. The pose, when requested, is the tag frame (x right, y down,
    z into the tag, as seen by the camera) expressed in the optical frame."""

    tag_id: int
    corners: np.ndarray
    centre: np.ndarray
    decision_margin: float
    hamming: int
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None
    pose_error: float | None = None


@functools.cache
def _detector(family: str, decimate: float) -> ctypes._Pointer:
    lib = _lib()
    det = lib.apriltag_detector_create()
    det.contents.nthreads = 1
    det.contents.quad_decimate = decimate
    det.contents.refine_edges = True
    lib.apriltag_detector_add_family_bits(det, _family(family), 2)
    return det


def _matd(ptr: int, rows: int, cols: int) -> np.ndarray:
    """Copy a matd_t (two unsigned ints, then row-major doubles) into numpy."""
    data = ctypes.cast(ptr + 2 * ctypes.sizeof(ctypes.c_uint), ctypes.POINTER(ctypes.c_double))
    return np.ctypeslib.as_array(data, shape=(rows * cols,)).reshape(rows, cols).copy()


def detect(
    gray: np.ndarray,
    family: str = "tag36h11",
    *,
    tag_size: float | None = None,
    camera_k: np.ndarray | None = None,
    decimate: float = 1.0,
) -> list[Detection]:
    """Run the real detector on a grey image; with tag_size (black edge, m) and K, add pose."""
    img = np.ascontiguousarray(gray, dtype=np.uint8)
    if img.ndim != 2:
        raise ValueError(f"detect() needs a 2-D grey image, got shape {img.shape}")
    lib = _lib()
    im = _ImageU8(
        img.shape[1],
        img.shape[0],
        img.strides[0],
        img.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8)),
    )
    zarr = lib.apriltag_detector_detect(_detector(family, decimate), ctypes.byref(im))
    out = []
    try:
        z = zarr.contents
        pointers = ctypes.cast(z.data, ctypes.POINTER(ctypes.POINTER(_Detection)))
        for i in range(z.size):
            d = pointers[i]
            det = d.contents
            kwargs: dict[str, Any] = {}
            if tag_size is not None and camera_k is not None:
                info = _DetectionInfo(
                    d,
                    tag_size,
                    camera_k[0][0],
                    camera_k[1][1],
                    camera_k[0][2] + DETECTOR_PIXEL_OFFSET,
                    camera_k[1][2] + DETECTOR_PIXEL_OFFSET,
                )
                pose = _Pose()
                err = lib.estimate_tag_pose(ctypes.byref(info), ctypes.byref(pose))
                kwargs = {
                    "rotation": _matd(pose.R, 3, 3),
                    "translation": _matd(pose.t, 3, 1).ravel(),
                    "pose_error": float(err),
                }
                _free()(pose.R)
                _free()(pose.t)
            out.append(
                Detection(
                    tag_id=det.id,
                    corners=np.array(det.p) - DETECTOR_PIXEL_OFFSET,
                    centre=np.array(det.c) - DETECTOR_PIXEL_OFFSET,
                    decision_margin=float(det.decision_margin),
                    hamming=det.hamming,
                    **kwargs,
                )
            )
    finally:
        lib.apriltag_detections_destroy(zarr)
    return out
