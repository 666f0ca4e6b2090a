//! The guided calibration on the panel's session (see the parent module's docs): the step
//! machine's actions carried out, test poses paced to the wall clock, refusals shown.

use super::{client, Error, Session};
use crate::{motion, msg};
use quad_host::link::Link;
use quad_host::ops::calibrate::guide::{self, Action, Guide, Refusal};
use quad_protocol::{Flags, NackReason};
use std::time::{Duration, Instant};

/// How often the state is read and published while the guided calibration waits for a test
/// pose (or the stand-up that switches the outputs on) to end.
pub const GUIDE_POLL: Duration = Duration::from_millis(100);

/// The longest a test pose of the guided calibration may take, link time.
pub const GUIDE_MOTION_LIMIT: Duration = Duration::from_secs(60);

impl<L: Link> Session<L> {
    /// Lets `d` of link time pass, then waits until the wall clock has caught up with the link
    /// time since `link_start` (at `wall_start`): a simulated device's motion then runs at its
    /// real pace.
    fn idle_paced(
        &mut self,
        d: Duration,
        wall_start: Instant,
        link_start: Duration,
    ) -> Result<(), Error> {
        self.idle(d)?;
        let link = self.link_elapsed().saturating_sub(link_start);
        if let Some(ahead) = link.checked_sub(wall_start.elapsed()) {
            std::thread::sleep(ahead);
        }
        Ok(())
    }

    /// Reads the state every [`GUIDE_POLL`], publishing each, until no motion runs.
    fn wait_motion(&mut self, publish: &dyn Fn(&Session<L>)) -> Result<(), Error> {
        let (wall, link) = (Instant::now(), self.link_elapsed());
        loop {
            self.poll()?;
            publish(self);
            if self.motion.kind.is_none() {
                return match self.motion.fault {
                    Some(fault) => Err(Error::MotionFault(fault)),
                    None => Ok(()),
                };
            }
            if self.link_elapsed().saturating_sub(link) > GUIDE_MOTION_LIMIT {
                return Err(Error::NoEnd(GUIDE_MOTION_LIMIT));
            }
            self.idle_paced(GUIDE_POLL, wall, link)?;
        }
    }

    /// Runs a test pose of the guided calibration to its end.
    fn guide_test(
        &mut self,
        pose: guide::TestPose,
        publish: &dyn Fn(&Session<L>),
    ) -> Result<(), Error> {
        let (start, velocity) = pose.motion(self.pose_config.stance_height_m);
        self.motion_command(&motion::Command::Start(start))?;
        publish(self);
        if let Some(v) = velocity {
            let (wall, link) = (Instant::now(), self.link_elapsed());
            let hold = Duration::from_secs_f32(v.duration_s);
            while self.link_elapsed().saturating_sub(link) < hold {
                self.motion_command(&motion::Command::Velocity(motion::VelocityMsg {
                    forward_m_s: v.forward_m_s,
                    lateral_m_s: v.lateral_m_s,
                    yaw_rate_rad_s: v.yaw_rate_rad_s,
                }))?;
                publish(self);
                self.idle_paced(GUIDE_POLL, wall, link)?;
            }
            self.motion_command(&motion::Command::Stop)?;
        }
        self.wait_motion(publish)
    }

    /// Carries out one action of the guided calibration.
    fn guide_act(&mut self, action: &Action, publish: &dyn Fn(&Session<L>)) -> Result<(), Error> {
        match *action {
            Action::OutputsOn if self.readback.flags.contains(Flags::OUTPUTS_ENABLED) => Ok(()),
            Action::OutputsOn => {
                self.motion_command(&motion::Command::Start(
                    quad_protocol::MotionCommand::StandUp,
                ))?;
                self.wait_motion(publish)
            }
            Action::SetJoints { angles_rad } => self.set_joints(angles_rad),
            Action::SetCalibration { servo, calibration } => {
                self.set_calibration(servo, calibration)
            }
            Action::Save => self.save_calibration(),
            Action::Test(pose) => self.guide_test(pose, publish),
        }
    }

    /// `guide_start` or `guide_key`: the step machine's actions carried out, the state
    /// published after each (see the module docs).
    ///
    /// # Errors
    /// [`Error::Guide`] when the device's robot is not known or has no calibration posture,
    /// [`Error::NoGuide`] for a key without a guide, link failures. A device refusal is the
    /// guide's message, not an error.
    pub fn guide_command(
        &mut self,
        cmd: &msg::ClientMsg,
        publish: &dyn Fn(&Session<L>),
    ) -> Result<(), Error> {
        let mut g = match *cmd {
            msg::ClientMsg::GuideStart => {
                if self.guide.as_ref().is_some_and(|g| !g.step().is_done()) {
                    return Err(Error::Guide(
                        "one is running: abort it first (q)".to_owned(),
                    ));
                }
                let robot = self.robot;
                self.read_calibration()?;
                Guide::new(&robot, self.calibration).map_err(|e| Error::Guide(e.to_string()))?
            }
            msg::ClientMsg::GuideKey { key } => {
                let mut g = self.guide.take().ok_or(Error::NoGuide)?;
                g.key(key);
                g
            }
            _ => return Ok(()),
        };
        let result = loop {
            let Some(action) = g.next_action() else {
                break Ok(());
            };
            // The state shows the guide's step while its action runs.
            self.guide = Some(g.clone());
            let done = self.guide_act(&action, publish);
            match refusal(done) {
                Ok(answer) => g.answer(answer),
                Err(e) => break Err(e),
            }
            self.guide = Some(g.clone());
            publish(self);
        };
        self.guide = Some(g);
        result
    }
}

/// A refusal (the device's, or a check of the host that the device runs alike) as the guided
/// calibration's [`Refusal`]; any other error as it is.
fn refusal(result: Result<(), Error>) -> Result<Result<(), Refusal>, Error> {
    let refused = |request, reason, sent| {
        Ok(Err(Refusal {
            request,
            reason,
            sent,
        }))
    };
    match result {
        Ok(()) => Ok(Ok(())),
        Err(Error::Refused { request, reason }) => refused(request, reason, true),
        Err(Error::MotionRefused { request, reason }) => {
            refused(client::request_name(&request), reason, true)
        }
        Err(Error::Motion { request, reason }) => {
            refused(client::request_name(&request), reason, false)
        }
        Err(Error::MotionFault(reason)) => refused("StartMotion", reason, true),
        Err(Error::BadCalibration { source, .. }) => {
            refused("SetCalibration", NackReason::BadCalibration(source), false)
        }
        Err(Error::Travel { servo, source }) => refused(
            "SetCalibration",
            NackReason::ServoRange {
                leg: servo.leg,
                joint: servo.joint,
                fault: source,
            },
            false,
        ),
        Err(e) => Err(e),
    }
}
