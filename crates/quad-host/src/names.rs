//! Names of kin-core's choices as the command line and files write them, for the types that
//! kin-core does not name itself ([`KneeBend`], [`ReachPolicy`]); [`kin_core::RotationOrder`]
//! and [`kin_core::motion::path::PathKind`] have their own `name` and `parse`.

use kin_core::{KneeBend, ReachPolicy};

/// The knee bends and their names (`--knee`, `knee_bend` in robot files).
pub const KNEE_BENDS: [(&str, KneeBend); 2] = [
    ("backward", KneeBend::Backward),
    ("forward", KneeBend::Forward),
];

/// The names of [`KNEE_BENDS`].
pub const KNEE_BEND_NAMES: [&str; 2] = ["backward", "forward"];

/// The values of [`KNEE_BENDS`].
pub const KNEE_BEND_VALUES: [KneeBend; 2] = [KneeBend::Backward, KneeBend::Forward];

/// The reach policies and their names (`--policy`).
pub const REACH_POLICIES: [(&str, ReachPolicy); 2] = [
    ("reject", ReachPolicy::Reject),
    ("clamp", ReachPolicy::Clamp),
];

/// The values of [`REACH_POLICIES`].
pub const REACH_POLICY_VALUES: [ReachPolicy; 2] = [ReachPolicy::Reject, ReachPolicy::Clamp];

/// The knee bend named `name` (lower case), if any.
pub fn knee_bend(name: &str) -> Option<KneeBend> {
    KNEE_BENDS.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// The lower-case name of a knee bend.
pub fn knee_bend_name(bend: KneeBend) -> &'static str {
    match bend {
        KneeBend::Backward => "backward",
        KneeBend::Forward => "forward",
    }
}

/// The lower-case name of a reach policy.
pub fn reach_policy_name(policy: ReachPolicy) -> &'static str {
    match policy {
        ReachPolicy::Reject => "reject",
        ReachPolicy::Clamp => "clamp",
    }
}

/// The reach policy named `name` (lower case), if any.
pub fn reach_policy(name: &str) -> Option<ReachPolicy> {
    REACH_POLICIES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, p)| *p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_reads_back() {
        for (name, bend) in KNEE_BENDS {
            assert_eq!(knee_bend(name), Some(bend));
            assert_eq!(knee_bend_name(bend), name);
        }
        assert_eq!(KNEE_BEND_NAMES, KNEE_BENDS.map(|(n, _)| n));
        assert_eq!(KNEE_BEND_VALUES, KNEE_BENDS.map(|(_, b)| b));
        assert_eq!(REACH_POLICY_VALUES, REACH_POLICIES.map(|(_, p)| p));
        for (name, policy) in REACH_POLICIES {
            assert_eq!(reach_policy(name), Some(policy));
            assert_eq!(reach_policy_name(policy), name);
        }
        assert_eq!(knee_bend("sideways"), None);
    }
}
