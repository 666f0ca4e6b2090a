"""quadkin: the quadruped's kinematics, motion laws and device client, from Rust.

Units are in every name: metres (``_m``), radians (``_rad``), seconds (``_s``). Frames are
REP 103 (x forward, y left, z up); legs FL, FR, RL, RR; joints abduction, hip, knee.

Batch calls take float32 or float64 numpy arrays of shape (N, 3), (N, 4, 3) or (N, 6) and
return float32 arrays with an int8 reach code per row (``OK``, ``TOO_FAR``, ``TOO_CLOSE``,
``INSIDE_OFFSET``, ``JOINT_LIMIT``, ``NON_FINITE``; names in ``CODE_NAMES``): a row that fails
gets its code and zeros, never NaN and never an exception.

>>> import numpy as np, quadkin
>>> robot = quadkin.Robot("shahriar2023")
>>> angles_rad, code = robot.leg_ik("FL", np.array([[0.0, 0.05, -0.25]]))
"""

from ._quadkin import (  # noqa: F401
    CODE_NAMES,
    INSIDE_OFFSET,
    JOINT_LIMIT,
    JOINTS,
    LEGS,
    NON_FINITE,
    OK,
    SINGULARITY_THRESHOLD,
    TOO_CLOSE,
    TOO_FAR,
    Device,
    DeviceError,
    LinkError,
    NackError,
    NoAnswerError,
    ProtocolError,
    QuadkinError,
    Robot,
    UnreachableError,
    VersionError,
    batch_form,
    decode_answer,
    encode_request,
    motion_laws,
    sample_motion,
    set_batch_form,
)

__all__ = [
    "CODE_NAMES",
    "INSIDE_OFFSET",
    "JOINT_LIMIT",
    "JOINTS",
    "LEGS",
    "NON_FINITE",
    "OK",
    "SINGULARITY_THRESHOLD",
    "TOO_CLOSE",
    "TOO_FAR",
    "Device",
    "DeviceError",
    "LinkError",
    "NackError",
    "NoAnswerError",
    "ProtocolError",
    "QuadkinError",
    "Robot",
    "UnreachableError",
    "VersionError",
    "batch_form",
    "motion_laws",
    "sample_motion",
    "set_batch_form",
]
