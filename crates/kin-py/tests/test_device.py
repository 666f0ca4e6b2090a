"""The device client against the simulated controller (the firmware's device logic on the
host's maths): handshake, poses, feet, joints, motions, velocity, calibration, state, and the
typed exceptions of refusals and absent devices."""

import numpy as np
import pytest

import quadkin


@pytest.fixture
def device():
    return quadkin.Device.sim("shahriar2023")


def test_hello_and_state(device):
    info = device.hello()
    assert info["robot"] == "shahriar2023" and info["version"] >> 8 == 2
    assert device.info == info
    state = device.state()
    assert state["angles_rad"].shape == (4, 3)
    assert state["pulses_half_us"].shape == (4, 3)
    assert state["outputs_enabled"] is False


def test_body_pose_equals_the_hosts_body_ik(device):
    robot = quadkin.Robot("shahriar2023")
    h = device.info["stance_height_m"]
    order = device.info["rotation_order"]
    pose = np.array([0.05, -0.03, 0.1, 0.01, 0.0, 0.02])
    rb = device.set_body_pose(pose)
    angles, code, _ = robot.body_ik(pose[None], stance_height_m=h, rotation_order=order)
    assert code[0] == quadkin.OK
    # The simulated device runs the host's maths: the same bits.
    assert np.array_equal(rb["angles_rad"], angles[0])


def test_feet_and_joints(device):
    robot = quadkin.Robot("shahriar2023")
    feet = robot.stance_feet_m(0.35)
    rb = device.set_feet(feet)
    assert rb["angles_rad"].shape == (4, 3)
    q = np.tile([0.0, 0.3, -0.6], (4, 1))
    rb = device.set_joints(q)
    assert np.allclose(rb["angles_rad"], q)


def test_refusals_carry_reason_and_field(device):
    with pytest.raises(quadkin.NackError) as e:
        device.set_body_pose([0, 0, 0, 0, 0, 5.0])
    assert e.value.reason == "out_of_range" and e.value.field == "z_m"
    assert e.value.request == "SetBodyPose" and e.value.port == "sim"
    with pytest.raises(quadkin.NackError) as e:
        device.set_body_pose([0, 0, 0, 0, 0, np.nan])
    assert e.value.reason == "non_finite"
    with pytest.raises(quadkin.NackError) as e:
        device.start_sway("roll", 0.1, 2.0)
    assert e.value.reason == "outputs_disabled"
    with pytest.raises(quadkin.NackError) as e:
        device.set_velocity(0.1)
    assert e.value.reason == "not_walking"
    assert isinstance(e.value, quadkin.DeviceError)
    with pytest.raises(ValueError, match=r"\[6\]"):
        device.set_body_pose([0, 0, 0])


def test_motions_and_velocity(device):
    status = device.stand_up()
    assert status["kind"] == "stand_up" and status["readback"]["outputs_enabled"]
    device.idle(3.0)
    assert device.motion_status()["kind"] is None
    status = device.start_sway("roll", 0.1, 2.0, duration_s=2.0)
    assert status["kind"] == "sway"
    with pytest.raises(quadkin.NackError) as e:
        device.start_sway("roll", 0.1, 2.0)
    assert e.value.reason == "motion_running"
    device.stop_motion()
    device.idle(4.0)
    assert device.motion_status()["kind"] is None
    with pytest.raises(quadkin.NackError) as e:
        device.start_sway("roll", 10.0, 2.0)
    assert e.value.reason == "invalid_parameter" and e.value.param == "amplitude_rad"
    assert e.value.problem == "out_of_range"
    h = device.info["stance_height_m"]
    device.start_walk("trot", body_height_m=h, step_height_m=0.03, cycle_s=0.8)
    status = device.set_velocity(0.05)
    assert status["kind"] == "walk"
    device.stop_motion()


def test_calibration_get_set_save(device, tmp_path):
    c = device.calibration("FL", "hip")
    assert set(c) == {"zero_rad", "reversed", "us_per_rad", "center_us", "min_us", "max_us"}
    c["center_us"] = 1510
    rb = device.set_calibration("FL", "hip", **c)
    assert rb["calibration_unsaved"]
    assert device.calibration(0, "hip")["center_us"] == 1510
    bad = dict(c, min_us=2000, max_us=1000)
    with pytest.raises(quadkin.NackError) as e:
        device.set_calibration("FL", "hip", **bad)
    assert e.value.reason == "bad_calibration" and e.value.fault == "bad_bounds"
    assert not device.save_calibration()["calibration_unsaved"]
    storage = tmp_path / "eeprom.bin"
    d1 = quadkin.Device.sim(storage=storage)
    knee = dict(d1.calibration("RR", "knee"), center_us=1510)
    d1.set_calibration("RR", "knee", **knee)
    d1.save_calibration()
    d2 = quadkin.Device.sim(storage=storage)
    assert d2.calibration("RR", "knee")["center_us"] == 1510


def test_absent_device_and_non_preset_robot():
    with pytest.raises(quadkin.LinkError) as e:
        quadkin.Device.serial("/dev/quadkin-no-such-port")
    assert e.value.port == "/dev/quadkin-no-such-port"
    assert "/dev/quadkin-no-such-port" in str(e.value)
    with pytest.raises(ValueError, match="preset"):
        quadkin.Device.sim("examples/robots/fernando2025.toml")
