"""Type stubs of the compiled module quadkin._quadkin (re-exported by quadkin)."""

from os import PathLike
from typing import Any, Literal, Optional, TypedDict, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

Leg = Union[Literal["FL", "FR", "RL", "RR"], int]
Joint = Literal["abduction", "hip", "knee"]
Policy = Literal["reject", "clamp"]
RotationOrder = Literal["xyz", "xzy", "yxz", "yzx", "zxy", "zyx"]
F32 = NDArray[np.float32]
I8 = NDArray[np.int8]

OK: int
TOO_FAR: int
TOO_CLOSE: int
INSIDE_OFFSET: int
JOINT_LIMIT: int
NON_FINITE: int
CODE_NAMES: list[str]
SINGULARITY_THRESHOLD: float
LEGS: list[str]
JOINTS: list[str]

class QuadkinError(Exception): ...

class UnreachableError(QuadkinError):
    leg: str
    code: int
    reason: str

class DeviceError(QuadkinError):
    port: str

class LinkError(DeviceError): ...

class NoAnswerError(DeviceError):
    request: str

class NackError(DeviceError):
    request: str
    reason: str
    detail: str
    leg: Optional[str]
    joint: Optional[str]
    field: Optional[str]
    param: Optional[str]
    problem: Optional[str]
    fault: Optional[str]

class VersionError(DeviceError):
    device_version: int

class ProtocolError(DeviceError): ...

class Robot:
    """A robot description with its kinematics over numpy arrays."""

    def __init__(self, spec: str) -> None: ...
    @staticmethod
    def from_toml(text: str) -> Robot: ...
    @staticmethod
    def presets() -> list[str]: ...
    @property
    def spec(self) -> Optional[str]: ...
    @property
    def d_lat_m(self) -> float: ...
    @property
    def d_ax_m(self) -> float: ...
    @property
    def femur_m(self) -> float: ...
    @property
    def tibia_m(self) -> float: ...
    @property
    def body_length_m(self) -> float: ...
    @property
    def body_width_m(self) -> float: ...
    @property
    def joint_min_rad(self) -> F32: ...
    @property
    def joint_max_rad(self) -> F32: ...
    @property
    def knee_bend(self) -> Literal["backward", "forward"]: ...
    def with_knee_bend(self, knee_bend: Literal["backward", "forward"]) -> Robot: ...
    def hip_in_body_m(self, leg: Leg) -> F32: ...
    def stance_feet_m(self, stance_height_m: float) -> F32: ...
    def leg_ik(
        self, leg: Leg, foot_in_hip_m: ArrayLike, policy: Policy = "reject"
    ) -> tuple[F32, I8]:
        """(N, 3) feet in the hip frame, m → ((N, 3) angles, rad; (N,) reach codes)."""
    def leg_ik_one(
        self, leg: Leg, x_m: float, y_m: float, z_m: float, policy: Policy = "reject"
    ) -> tuple[float, float, float]:
        """One foot → (abduction_rad, hip_rad, knee_rad); raises UnreachableError."""
    def leg_fk(self, leg: Leg, angles_rad: ArrayLike) -> tuple[F32, I8]:
        """(N, 3) angles, rad → ((N, 3) feet in the hip frame, m; (N,) codes)."""
    def leg_jacobian(self, leg: Leg, angles_rad: ArrayLike) -> tuple[F32, I8]:
        """(N, 3) angles, rad → ((N, 3, 3) Jacobian, m/rad; (N,) codes)."""
    def singularity(self, leg: Leg, angles_rad: ArrayLike) -> tuple[F32, I8]:
        """(N, 3) angles, rad → ((N,) inverse condition number in [0, 1]; (N,) codes)."""
    def body_ik(
        self,
        pose: ArrayLike,
        feet_in_world_m: Optional[ArrayLike] = None,
        stance_height_m: Optional[float] = None,
        rotation_order: Optional[RotationOrder] = None,
        policy: Policy = "reject",
    ) -> tuple[F32, I8, I8]:
        """(N, 6) poses → ((N, 4, 3) angles, rad; (N,) codes; (N,) failing leg or -1)."""
    def body_fk(
        self,
        pose: ArrayLike,
        angles_rad: ArrayLike,
        rotation_order: Optional[RotationOrder] = None,
    ) -> tuple[F32, I8]:
        """(N, 6) poses and (N, 4, 3) angles, rad → ((N, 4, 3) feet in the world, m; codes)."""

class MotionSamples(TypedDict):
    t_s: NDArray[np.float64]
    angles_rad: F32
    feet_in_world_m: F32
    pose: F32
    code: I8
    leg: I8
    rotation_order: str

def sample_motion(
    law: str,
    robot: str = "shahriar2023",
    duration_s: float = 2.0,
    rate_hz: float = 100.0,
    *,
    stance_height_m: Optional[float] = None,
    rotation_order: Optional[RotationOrder] = None,
    amplitude_rad: Optional[float] = None,
    period_s: Optional[float] = None,
    yaw_rate_rad_s: Optional[float] = None,
    step_period_s: Optional[float] = None,
    lift_height_m: Optional[float] = None,
    path: Optional[str] = None,
    stride_m: Optional[float] = None,
    step_height_m: Optional[float] = None,
    duty_factor: Optional[float] = None,
    cycle_s: Optional[float] = None,
    forward_m_s: Optional[float] = None,
    lateral_m_s: Optional[float] = None,
    yaw_rad_s: Optional[float] = None,
) -> MotionSamples: ...
def motion_laws() -> list[str]: ...
def batch_form() -> Literal["avx512", "avx2", "portable"]:
    """The form of the batch solves the batch calls use: the widest this CPU runs (AVX-512 with
    16 lanes, AVX2 with 8, or the portable one) unless :func:`set_batch_form` chose another;
    all give the same bits."""
def set_batch_form(form: Optional[Literal["avx512", "avx2", "portable"]]) -> None:
    """Makes the batch calls use ``form`` (``None``: the widest this CPU runs again), to compare
    the forms or measure one. Raises ``ValueError`` for another name or a form this CPU cannot
    run."""

class Readback(TypedDict):
    angles_rad: F32
    pulses_half_us: NDArray[np.uint16]
    flags: int
    clamped: bool
    limited: bool
    outputs_enabled: bool
    failsafe_active: bool
    calibration_unsaved: bool
    calibration_default: bool
    watchdog_reset: bool
    frames_ok: int
    frames_bad: int

class MotionStatus(TypedDict):
    kind: Optional[str]
    stage: str  # approach, run, stopping, leave, idle
    t_s: float
    phase: float
    fault: Optional[str]
    readback: Readback

class Calibration(TypedDict):
    zero_rad: float
    reversed: bool
    us_per_rad: float
    center_us: int
    min_us: int
    max_us: int

class Device:
    """A connected device (the handshake runs on opening)."""

    @staticmethod
    def sim(
        robot: str = "shahriar2023",
        baud: int = 115200,
        storage: Optional[Union[str, PathLike[str]]] = None,
        retries: int = 10,
    ) -> Device: ...
    @staticmethod
    def emulator(
        elf: Optional[Union[str, PathLike[str]]] = None,
        baud: int = 115200,
        storage: Optional[Union[str, PathLike[str]]] = None,
        retries: int = 10,
        bridge: Optional[Union[str, PathLike[str]]] = None,
    ) -> Device:
        """The firmware in simavr, run by the quad-link-bridge program."""
    @staticmethod
    def serial(port: str, baud: int = 115200, retries: int = 10) -> Device: ...
    @property
    def port(self) -> str: ...
    @property
    def info(self) -> dict[str, Any]: ...
    def hello(self) -> dict[str, Any]: ...
    def state(self) -> Readback: ...
    def set_outputs(self, enabled: bool) -> Readback: ...
    def set_body_pose(self, pose: ArrayLike) -> Readback: ...
    def set_feet(self, feet_in_body_m: ArrayLike) -> Readback: ...
    def set_joints(self, angles_rad: ArrayLike) -> Readback: ...
    def set_joint_speed_limit(self, joint_speed_limit_rad_s: float) -> Readback: ...
    def calibration(self, leg: Leg, joint: Joint) -> Calibration: ...
    def set_calibration(
        self,
        leg: Leg,
        joint: Joint,
        *,
        zero_rad: float,
        reversed: bool,
        us_per_rad: float,
        center_us: int,
        min_us: int,
        max_us: int,
    ) -> Readback: ...
    def save_calibration(self) -> Readback: ...
    def stand_up(self) -> MotionStatus: ...
    def sit(self) -> MotionStatus: ...
    def rest(self) -> MotionStatus: ...
    def start_sway(
        self,
        axis: Literal["roll", "pitch", "yaw"],
        amplitude_rad: float,
        period_s: float,
        duration_s: Optional[float] = None,
    ) -> MotionStatus: ...
    def start_yaw_turn(
        self,
        yaw_rate_rad_s: float,
        step_period_s: float,
        lift_height_m: float,
        duration_s: Optional[float] = None,
    ) -> MotionStatus: ...
    def start_foot_path(
        self,
        path: str,
        stride_m: float,
        step_height_m: float,
        duty_factor: float,
        cycle_s: float,
        leg: Optional[Leg] = None,
        duration_s: Optional[float] = None,
    ) -> MotionStatus: ...
    def start_walk(
        self,
        gait: Literal["trot", "walk"],
        body_height_m: float,
        step_height_m: float,
        cycle_s: float,
        velocity_timeout_ms: int = 500,
    ) -> MotionStatus: ...
    def stop_motion(self) -> MotionStatus: ...
    def motion_status(self) -> MotionStatus: ...
    def set_velocity(
        self, forward_m_s: float, lateral_m_s: float = 0.0, yaw_rate_rad_s: float = 0.0
    ) -> MotionStatus: ...
    def idle(self, duration_s: float) -> None: ...



def encode_request(message_json: str) -> bytes:
    """The frame (COBS, CRC, both delimiters) of a host-to-device message in its JSON form,
    e.g. ``'{"seq": 1, "request": "get_state"}'``; ``ValueError`` names what is wrong."""

def decode_answer(frame: bytes) -> str:
    """The JSON form of the device-to-host message in one whole frame; ``ValueError`` when the
    bytes are not one readable frame."""
