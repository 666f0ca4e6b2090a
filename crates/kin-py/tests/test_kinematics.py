"""Batch kinematics: round trips against the Rust results (quadctl's CSV, shortest round-trip
f32 text, compared bit for bit), FK∘IK, shapes, dtypes, reach codes and bad input."""

import csv
import io
import subprocess

import numpy as np
import pytest

import quadkin

# FK∘IK round trip bound, m: f32 rounding of a ~0.5 m chain (kin-core's own tests use the same
# order of magnitude).
ROUND_TRIP_TOL_M = 2e-6


def random_feet(n: int, seed: int = 0) -> np.ndarray:
    """Feet in the hip frame of FL around the reachable workspace of shahriar2023 (and some
    beyond it), m."""
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [
            rng.uniform(-0.45, 0.45, n),
            rng.uniform(-0.3, 0.35, n),
            rng.uniform(-0.6, 0.1, n),
        ]
    )


def quadctl_ik(quadctl, robot: str, leg: str, feet: np.ndarray, policy="reject"):
    text = "leg,x_m,y_m,z_m\n" + "".join(
        f"{leg},{x!r},{y!r},{z!r}\n" for x, y, z in feet.astype(np.float32).tolist()
    )
    out = subprocess.run(
        [str(quadctl), "ik", "--robot", robot, "--policy", policy],
        input=text,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    rows = [r for r in csv.DictReader(io.StringIO(out))]
    assert len(rows) == len(feet)
    return rows


@pytest.mark.parametrize("robot_name", ["shahriar2023", "fernando2025"])
def test_leg_ik_equals_quadctl_bit_for_bit(quadctl, robot_name):
    robot = quadkin.Robot(robot_name)
    feet = random_feet(400, seed=1).astype(np.float32)
    angles, code = robot.leg_ik("FL", feet)
    rows = quadctl_ik(quadctl, robot_name, "FL", feet)
    solved = 0
    for i, row in enumerate(rows):
        status = row["status"]
        assert quadkin.CODE_NAMES[code[i]] == status.split(" ")[0], (i, status)
        if status == "ok":
            want = np.array(
                [float(row[k]) for k in ("abduction_rad", "hip_rad", "knee_rad")],
                dtype=np.float32,
            )
            assert np.array_equal(angles[i], want), (i, angles[i], want)
            solved += 1
        else:
            assert np.all(angles[i] == 0.0)
    assert solved > 50


def test_fk_of_ik_returns_the_target():
    robot = quadkin.Robot("shahriar2023")
    feet = random_feet(20_000, seed=2)
    for leg in quadkin.LEGS:
        angles, code = robot.leg_ik(leg, feet)
        back, fk_code = robot.leg_fk(leg, angles)
        ok = code == quadkin.OK
        assert ok.sum() > 1000
        assert np.all(fk_code == quadkin.OK)
        err = np.abs(back[ok] - feet[ok].astype(np.float32)).max()
        assert err < ROUND_TRIP_TOL_M, err


def test_single_solve_equals_batch_and_raises_typed_error():
    robot = quadkin.Robot("shahriar2023")
    feet = random_feet(50, seed=3).astype(np.float32)
    angles, code = robot.leg_ik("RR", feet)
    for i, (x, y, z) in enumerate(feet.tolist()):
        if code[i] == quadkin.OK:
            assert robot.leg_ik_one("RR", x, y, z) == tuple(angles[i].tolist())
        else:
            with pytest.raises(quadkin.UnreachableError) as e:
                robot.leg_ik_one("RR", x, y, z)
            assert e.value.code == code[i]
            assert e.value.reason == quadkin.CODE_NAMES[code[i]]
            assert e.value.leg == "RR"


def cpu_flags() -> set[str]:
    """The CPU's feature flags as Linux lists them (empty elsewhere)."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def test_batch_form_is_the_widest_the_cpu_runs():
    flags = cpu_flags()
    if not flags:  # Not Linux: the flags are unknown here.
        assert quadkin.batch_form() in ("avx512", "avx2", "portable")
        return
    if {"avx512f", "avx512vl", "avx512bw", "avx512dq"} <= flags:
        want = "avx512"
    elif "avx2" in flags:
        want = "avx2"
    else:
        want = "portable"
    assert quadkin.batch_form() == want


def test_every_form_the_cpu_runs_gives_the_same_bits():
    widest = quadkin.batch_form()
    forms = ["avx512", "avx2", "portable"]
    runnable = forms[forms.index(widest):]
    robot = quadkin.Robot("shahriar2023")
    # Beyond two slices of the parallel path, with a tail; bad rows among them.
    feet = random_feet(40_001, seed=9)
    feet[::997] = np.nan
    feet[5::1009, 2] = -10.0
    rng = np.random.default_rng(11)
    poses = rng.uniform([-0.3, -0.3, -0.5, -0.05, -0.05, -0.05],
                        [0.3, 0.3, 0.5, 0.05, 0.05, 0.05], (40_001, 6))
    angles_fk = rng.uniform(-2.0, 2.0, (40_001, 3))
    results = {}
    try:
        for form in runnable:
            quadkin.set_batch_form(form)
            assert quadkin.batch_form() == form
            results[form] = (
                robot.leg_ik("FR", feet),
                robot.leg_ik("FR", feet, policy="clamp"),
                robot.leg_fk("RL", angles_fk),
                robot.body_ik(poses, stance_height_m=0.25),
            )
    finally:
        quadkin.set_batch_form(None)
    assert quadkin.batch_form() == widest
    portable = results["portable"]
    for form in runnable:
        for got, want in zip(results[form], portable):
            for g, w in zip(got, want):
                assert g.dtype == w.dtype and g.tobytes() == w.tobytes(), form
    assert (portable[0][1] == quadkin.NON_FINITE).sum() == len(feet[::997])
    with pytest.raises(ValueError, match="avx1024"):
        quadkin.set_batch_form("avx1024")
    assert quadkin.batch_form() == widest


def test_shapes_dtypes_and_large_batches_agree_with_small_ones():
    robot = quadkin.Robot("fernando2025")
    feet = random_feet(100_000, seed=4)
    angles, code = robot.leg_ik(0, feet)
    assert angles.shape == (100_000, 3) and angles.dtype == np.float32
    assert code.shape == (100_000,) and code.dtype == np.int8
    # The parallel path (large N) and the serial one (small N) give the same rows.
    a_small, c_small = robot.leg_ik(0, feet[:1000])
    assert np.array_equal(a_small, angles[:1000]) and np.array_equal(c_small, code[:1000])
    # float32 input, non-contiguous input, lists.
    a32, _ = robot.leg_ik(0, feet[:1000].astype(np.float32))
    assert np.array_equal(a32, a_small)
    strided = np.asfortranarray(feet[:1000])
    assert np.array_equal(robot.leg_ik(0, strided)[0], a_small)
    assert np.array_equal(robot.leg_ik(0, feet[:3].tolist())[0], a_small[:3])
    empty, ecode = robot.leg_ik(0, np.zeros((0, 3)))
    assert empty.shape == (0, 3) and ecode.shape == (0,)


def test_bad_rows_get_codes_never_nan():
    robot = quadkin.Robot("shahriar2023")
    feet = np.array(
        [
            [0.0, 0.044, -0.4],
            [np.nan, 0.0, -0.3],
            [np.inf, 0.0, -0.3],
            [1e300, 0.0, 0.0],
            [0.0, 0.0, -2.0],
            [0.0, 0.044, -0.01],
        ]
    )
    angles, code = robot.leg_ik("FL", feet)
    assert not np.isnan(angles).any()
    assert code.tolist()[:5] == [
        quadkin.OK,
        quadkin.NON_FINITE,
        quadkin.NON_FINITE,
        quadkin.NON_FINITE,
        quadkin.TOO_FAR,
    ]
    assert code[5] != quadkin.OK
    clamped, ccode = robot.leg_ik("FL", feet, policy="clamp")
    assert not np.isnan(clamped).any()
    assert ccode[1] == quadkin.NON_FINITE and ccode[4] == quadkin.TOO_FAR
    assert np.any(clamped[4] != 0.0)


@pytest.mark.parametrize(
    "bad, exc, message",
    [
        (np.zeros((4, 2)), ValueError, "(N, 3)"),
        (np.zeros(3), ValueError, "(N, 3)"),
        (np.zeros((2, 3), dtype=np.int64), TypeError, "(N, 3)"),
        (np.zeros((2, 3), dtype=np.complex128), TypeError, "(N, 3)"),
        ("not an array", TypeError, "(N, 3)"),
    ],
)
def test_wrong_shape_or_dtype_names_the_expected_shape(bad, exc, message):
    robot = quadkin.Robot("shahriar2023")
    with pytest.raises(exc, match=message.replace("(", r"\(").replace(")", r"\)")):
        robot.leg_ik("FL", bad)


def test_bad_arguments():
    robot = quadkin.Robot("shahriar2023")
    with pytest.raises(ValueError, match="leg"):
        robot.leg_ik("XX", np.zeros((1, 3)))
    with pytest.raises(ValueError, match="policy"):
        robot.leg_ik("FL", np.zeros((1, 3)), policy="maybe")
    with pytest.raises(ValueError, match="rotation_order"):
        robot.body_ik(np.zeros((1, 6)), stance_height_m=0.3, rotation_order="abc")
    with pytest.raises(ValueError, match=r"\(N, 4, 3\)"):
        robot.body_ik(np.zeros((2, 6)), feet_in_world_m=np.zeros((2, 3, 3)))
    with pytest.raises(OSError):
        quadkin.Robot("/nonexistent/robot.toml")


def test_body_ik_fk_round_trip_and_stance_equivalence():
    robot = quadkin.Robot("shahriar2023")
    rng = np.random.default_rng(5)
    n = 5000
    pose = np.column_stack(
        [
            rng.uniform(-0.2, 0.2, (n, 3)),
            rng.uniform(-0.03, 0.03, (n, 3)),
        ]
    )
    angles, code, leg = robot.body_ik(pose, stance_height_m=0.4)
    assert angles.shape == (n, 4, 3) and code.shape == (n,) and leg.shape == (n,)
    ok = code == quadkin.OK
    assert ok.sum() > n // 2
    assert np.all(leg[ok] == -1) and np.all(leg[~ok] >= 0)
    feet, fk_code = robot.body_fk(pose, angles)
    assert np.all(fk_code == quadkin.OK)
    stance = robot.stance_feet_m(0.4)
    err = np.abs(feet[ok] - stance[None]).max()
    assert err < 1e-5, err
    # Explicit feet (the same stance for every row) solve the same poses.
    a2, c2, _ = robot.body_ik(pose, feet_in_world_m=stance)
    assert np.array_equal(c2, code)
    assert np.abs(a2[ok] - angles[ok]).max() < 1e-4
    bad = pose.copy()
    bad[0, 0] = np.nan
    _, cbad, lbad = robot.body_ik(bad, stance_height_m=0.4)
    assert cbad[0] == quadkin.NON_FINITE and lbad[0] == 0


def test_jacobian_matches_finite_differences_and_singularity_measure():
    robot = quadkin.Robot("fernando2025")
    rng = np.random.default_rng(6)
    q = np.column_stack(
        [rng.uniform(-0.3, 0.3, 200), rng.uniform(-0.5, 0.8, 200), rng.uniform(-1.5, -0.3, 200)]
    )
    jac, code = robot.leg_jacobian("FR", q)
    assert jac.shape == (200, 3, 3) and np.all(code == quadkin.OK)
    h = 1e-3
    for j in range(3):
        dq = np.zeros(3)
        dq[j] = h
        plus, _ = robot.leg_fk("FR", q + dq)
        minus, _ = robot.leg_fk("FR", q - dq)
        fd = (plus.astype(np.float64) - minus) / (2 * h)
        assert np.abs(fd - jac[:, :, j]).max() < 1e-3
    ic, icode = robot.singularity("FR", q)
    assert ic.shape == (200,) and np.all((ic >= 0) & (ic <= 1))
    s = np.linalg.svd(jac.astype(np.float64), compute_uv=False)
    assert np.abs(ic - s[:, 2] / s[:, 0]).max() < 1e-3
    straight, _ = robot.singularity("FR", np.zeros((1, 3)))
    assert straight[0] < quadkin.SINGULARITY_THRESHOLD
    _, nan_code = robot.singularity("FR", np.array([[np.nan, 0, 0]]))
    assert nan_code[0] == quadkin.NON_FINITE


def test_robot_files_toml_and_urdf(tmp_path, root, quadctl):
    robot = quadkin.Robot("shahriar2023")
    assert robot.femur_m == pytest.approx(0.28) and robot.knee_bend == "backward"
    toml_files = sorted((root / "examples" / "robots").glob("*.toml"))
    assert toml_files, "examples/ has robot files"
    from_file = quadkin.Robot(str(toml_files[0]))
    from_text = quadkin.Robot.from_toml(toml_files[0].read_text())
    assert from_file.femur_m == from_text.femur_m
    urdf = tmp_path / "robot.urdf"
    subprocess.run(
        [str(quadctl), "export", "--format", "urdf", "--robot", "fernando2025", "--output", str(urdf)],
        check=True,
        capture_output=True,
    )
    from_urdf = quadkin.Robot(str(urdf))
    ref = quadkin.Robot("fernando2025")
    assert from_urdf.femur_m == pytest.approx(ref.femur_m, abs=1e-6)
    assert from_urdf.tibia_m == pytest.approx(ref.tibia_m, abs=1e-6)
    with pytest.raises(ValueError):
        quadkin.Robot.from_toml("[leg]\nfemur_m = -1\n")


def test_odd_arrays_answer_or_raise_typed_errors():
    robot = quadkin.Robot("shahriar2023")
    feet = random_feet(64, seed=7)
    want, _ = robot.leg_ik("FL", feet[::-1].copy())
    got, _ = robot.leg_ik("FL", feet[::-1])  # negative strides
    assert np.array_equal(got, want)
    for bad in (None, np.float64(1.0), np.zeros((2, 3), dtype=np.float16), [[1, 2], [3]]):
        with pytest.raises((TypeError, ValueError)):
            robot.leg_ik("FL", bad)
    with pytest.raises(ValueError, match=r"\(N, 4, 3\)"):
        robot.body_fk(np.zeros((2, 6)), np.zeros((2, 12)))
    with pytest.raises(ValueError, match="same N"):
        robot.body_fk(np.zeros((2, 6)), np.zeros((3, 4, 3)))
