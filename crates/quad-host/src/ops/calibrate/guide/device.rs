//! The guide's device end: the [`Device`] trait, the loop that carries out the queued actions
//! ([`settle`]) and the command line's device on an onboard-motion session ([`SessionDevice`]).

use super::{Action, Guide, Refusal, VelocityStep};
use crate::client;
use crate::link::Link;
use crate::ops::onboard::{self, Session};
use quad_protocol::Request;
use std::time::Duration;

/// The device end of the guide: carries out one [`Action`].
pub trait Device {
    /// A failure that ends the guide (the link), as opposed to a refusal.
    type Error;

    /// Carries out `action`: `Ok(Err(refusal))` when the device (or the host's range check)
    /// refused it.
    ///
    /// # Errors
    /// A link failure.
    fn act(&mut self, action: &Action) -> Result<Result<(), Refusal>, Self::Error>;
}

/// Carries out every action the guide has queued, one at a time, each answer to the guide.
///
/// # Errors
/// The device's failure; the guide then keeps the action in flight unanswered.
pub fn settle<D: Device>(guide: &mut Guide, device: &mut D) -> Result<(), D::Error> {
    while let Some(action) = guide.next_action() {
        let result = device.act(&action)?;
        guide.answer(result);
    }
    Ok(())
}

/// The guide's device on an onboard-motion [`Session`] (the command line's).
pub struct SessionDevice<'a, L> {
    /// The session.
    pub session: &'a mut Session<L>,
    /// How long a test pose may take, link time.
    pub limit: Duration,
    /// Sees every answer of a running test pose (the front end's status line).
    pub each: &'a mut dyn FnMut(&onboard::MotionAnswer),
}

/// A refused request as a [`Refusal`]; any other error as it is.
fn refusal(e: onboard::Error) -> Result<Result<(), Refusal>, onboard::Error> {
    match e {
        onboard::Error::Refused {
            request, reason, ..
        }
        | onboard::Error::Client(client::Error::Refused { request, reason }) => Ok(Err(Refusal {
            request,
            reason,
            sent: true,
        })),
        onboard::Error::NotSent {
            request, reason, ..
        } => Ok(Err(Refusal {
            request,
            reason,
            sent: false,
        })),
        onboard::Error::Fault(reason) => Ok(Err(Refusal {
            request: "StartMotion",
            reason,
            sent: true,
        })),
        other => Err(other),
    }
}

impl<L: Link> Device for SessionDevice<'_, L> {
    type Error = onboard::Error;

    fn act(&mut self, action: &Action) -> Result<Result<(), Refusal>, onboard::Error> {
        let done = match *action {
            Action::OutputsOn => self.session.stand_if_off(self.limit).map(|_| ()),
            Action::SetJoints { angles_rad } => self
                .session
                .client_mut()
                .ack(Request::SetJoints { angles_rad })
                .map(|_| ())
                .map_err(onboard::Error::from),
            Action::SetCalibration { servo, calibration } => self
                .session
                .client_mut()
                .ack(Request::SetCalibration { servo, calibration })
                .map(|_| ())
                .map_err(onboard::Error::from),
            Action::Save => self
                .session
                .client_mut()
                .ack(Request::SaveCalibration)
                .map(|_| ())
                .map_err(onboard::Error::from),
            Action::Test(pose) => {
                let (motion, velocity) =
                    pose.motion(self.session.info().pose_config.stance_height_m);
                let walk: Vec<VelocityStep> = velocity.into_iter().collect();
                onboard::run(self.session, &motion, &walk, self.limit, &mut *self.each).map(|_| ())
            }
        };
        match done {
            Ok(()) => Ok(Ok(())),
            Err(e) => refusal(e),
        }
    }
}
