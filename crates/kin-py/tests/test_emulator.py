"""The device client against the real firmware in simavr (through quad-link-bridge): the
handshake, a body pose within the firmware's angle tolerance of the host's IK, a refusal with
its field, calibration, an onboard motion, and the EEPROM file kept across power cycles."""

import numpy as np
import pytest

import quadkin

# |firmware angle − host angle| bound, rad: quad_host::client::AVR_ANGLE_TOLERANCE_RAD.
AVR_ANGLE_TOLERANCE_RAD = 2e-5


@pytest.fixture(scope="module")
def device(link_bridge, firmware_elf):
    return quadkin.Device.emulator(elf=firmware_elf, bridge=link_bridge)


def test_hello_pose_and_refusal(device):
    info = device.info
    assert info["robot"] == "shahriar2023" and device.port == "emulator"
    robot = quadkin.Robot(info["robot"])
    pose = np.array([0.1, -0.05, 0.08, 0.01, -0.01, 0.0])
    rb = device.set_body_pose(pose)
    angles, code, _ = robot.body_ik(
        pose[None], stance_height_m=info["stance_height_m"], rotation_order=info["rotation_order"]
    )
    assert code[0] == quadkin.OK
    assert np.abs(rb["angles_rad"] - angles[0]).max() <= AVR_ANGLE_TOLERANCE_RAD
    with pytest.raises(quadkin.NackError) as e:
        device.set_body_pose([0, 0, 0, 0, 0, 5.0])
    assert e.value.reason == "out_of_range" and e.value.field == "z_m"
    assert e.value.port == "emulator"


def test_calibration_and_motion(device):
    c = device.calibration("FR", "knee")
    assert c["min_us"] < c["center_us"] < c["max_us"]
    status = device.stand_up()
    assert status["kind"] == "stand_up"
    device.idle(2.5)
    assert device.motion_status()["kind"] is None
    assert device.state()["outputs_enabled"]


def test_eeprom_file_survives_a_power_cycle(link_bridge, firmware_elf, tmp_path):
    storage = tmp_path / "eeprom.bin"
    d1 = quadkin.Device.emulator(elf=firmware_elf, bridge=link_bridge, storage=storage)
    knee = dict(d1.calibration("RL", "knee"), center_us=1490)
    d1.set_calibration("RL", "knee", **knee)
    d1.save_calibration()
    del d1
    d2 = quadkin.Device.emulator(elf=firmware_elf, bridge=link_bridge, storage=storage)
    assert d2.calibration("RL", "knee")["center_us"] == 1490


def test_missing_bridge_or_firmware_is_a_link_error(link_bridge, tmp_path):
    with pytest.raises(quadkin.LinkError, match="cannot start"):
        quadkin.Device.emulator(bridge=tmp_path / "no-such-bridge")
    with pytest.raises(quadkin.LinkError) as e:
        quadkin.Device.emulator(elf=tmp_path / "missing.elf", bridge=link_bridge)
    assert e.value.port == "emulator"
