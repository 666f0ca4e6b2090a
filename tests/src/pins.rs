//! One servo channel's step between two consecutive pulses, as the emulator measures them,
//! against the joint-speed limiter's bound: the "no snap" check of the emulator tests.

use quad_host::emu::{Pulse, CYCLES_PER_US};

/// One timer tick of the pulse widths, µs: the rounding of each pulse.
pub const TICK_US: f64 = 0.5;

/// The joint step between the pulses `last` and `now` of one channel of gain `us_per_rad`, and
/// the most the limiter at `limit_rad_s` allows in one 20 ms period with the measurement's
/// slack: each edge is seen up to one simavr step late, and the widths are whole timer ticks.
/// Both rad.
pub fn step_and_bound_rad(
    last: &Pulse,
    now: &Pulse,
    us_per_rad: f64,
    limit_rad_s: f64,
) -> (f64, f64) {
    let d_us = (now.high_cycles as f64 - last.high_cycles as f64).abs() / CYCLES_PER_US as f64;
    let slack_us = (now.rise_step_cycles
        + now.fall_step_cycles
        + last.rise_step_cycles
        + last.fall_step_cycles) as f64
        / CYCLES_PER_US as f64
        + TICK_US;
    (
        d_us / us_per_rad,
        limit_rad_s * 0.02 + slack_us / us_per_rad,
    )
}
