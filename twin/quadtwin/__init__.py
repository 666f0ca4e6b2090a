"""quadtwin: the quadruped's physics twin in MuJoCo.

The Rust side (crate ``quad-twin``) writes the model (crate ``quad-model``) and drives the
loop: it steps the device controller frame by frame and sends each frame's servo pulses and
the joint angles they map to, through the device's own calibration, as JSON lines on this
process's standard input; ``quadtwin.runner`` holds each frame for its 20 ms, steps MuJoCo at
the model's time step, and answers every frame with the body state (pose, IMU readings,
contacts), so that a sensor can be fed back to the device later without changing the
coupling.

Modules:
- ``model``: loading a model written by ``quad-model`` and the names it relies on.
- ``servo``: the servo controller (duty cycle from the position error; the MJCF actuator
  applies the DC-motor law).
- ``runner``: the frame loop (``python -m quadtwin.runner``), with the IMU's samples.
- ``scenario``: the floor (level, a slope, tilting during the run) and a push on the body.
- ``metrics``: fall, yaw, distance, slip, torque and tracking figures of a run, the answer to
  a slope, a tilt or a push, and the IMU's samples with the true attitude.
- ``render``: offscreen pictures (GIF and PNG strip) and the metric plots.
- ``check_fk``: foot sites at given joint angles (the forward-kinematics agreement test).
"""
