// kin-core in the page: the WebAssembly module of crates/kin-wasm and its buffers.
//
// The module exports plain functions that read `kin_input()` and write `kin_output()`, two
// arrays of f32 in its memory (see crates/kin-wasm/src/lib.rs for the layouts).

const STATUS = ['ok', 'too_far', 'too_close', 'inside_offset', 'joint_limit', 'non_finite', 'unreachable'];
const LEGS = ['FL', 'FR', 'RL', 'RR'];

export async function loadKin(url) {
  const bytes = await (await fetch(url)).arrayBuffer();
  if (bytes.byteLength === 0) {
    throw new Error('kin.wasm is empty: the server was built without the wasm32-unknown-unknown target');
  }
  const { instance } = await WebAssembly.instantiate(bytes, {});
  const ex = instance.exports;
  const input = () => new Float32Array(ex.memory.buffer, ex.kin_input(), 32);
  const output = () => new Float32Array(ex.memory.buffer, ex.kin_output(), 64);
  const poseArray = (p) => [p.roll_rad, p.pitch_rad, p.yaw_rad, p.x_m, p.y_m, p.z_m];

  return {
    wasmBytes: bytes.byteLength,

    // robot: kin_core::Robot as the server serialises it.
    setRobot(robot) {
      input().set([
        robot.leg.d_lat_m, robot.leg.d_ax_m, robot.leg.femur_m, robot.leg.tibia_m,
        robot.body_length_m, robot.body_width_m,
        ...robot.limits.min_rad, ...robot.limits.max_rad,
        robot.knee_bend === 'Forward' ? 1 : 0,
      ]);
      const code = ex.kin_set_robot();
      if (code !== 0) throw new Error(`kin-core refused the robot (${code})`);
    },

    // Full-body IK at the stance, as the device solves it, with each leg's status and margins.
    preview(pose, stanceHeightM, order) {
      const inp = input();
      inp.set(poseArray(pose));
      inp[6] = stanceHeightM;
      const code = ex.kin_preview(order);
      if (code < 0) throw new Error(`kin_preview failed (${code})`);
      const out = output();
      const legs = LEGS.map((name, i) => ({
        name,
        status: STATUS[out[12 + i]] ?? 'unreachable',
        workspaceMarginM: out[16 + i],
        jointMarginRad: out[20 + i],
      }));
      return {
        reachable: code === 0,
        firstLeg: code > 0 ? LEGS[code - 1] : null,
        angles: Array.from(out.subarray(0, 12)),
        legs,
      };
    },

    // Every joint in the world frame: 4 legs x [hip mount, hip joint, knee, foot] x xyz.
    points(pose, angles, order) {
      const inp = input();
      inp.set(poseArray(pose));
      inp.set(angles, 6);
      const code = ex.kin_points(order);
      if (code < 0) throw new Error(`kin_points failed (${code})`);
      return Array.from(output().subarray(0, 48));
    },
  };
}
