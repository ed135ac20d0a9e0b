//! The ROS 2 managed-node state machine, as rcl_lifecycle defines it, for nav2's lifecycle
//! manager: the primary states unconfigured, inactive, active and finalized, and the
//! transitions between them (configure, cleanup, activate, deactivate, shutdown). Each
//! transition passes through its transition state (configuring, …) and, the bridge's callbacks
//! always succeeding, ends in its goal primary state. The bridge publishes only while
//! [`State::Active`].

use crate::msg::{LifecycleState, LifecycleTransition, TransitionDescription};

/// A primary state (`lifecycle_msgs/State` ids 1 to 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    Unconfigured,
    Inactive,
    Active,
    Finalized,
}

impl State {
    /// Its `lifecycle_msgs/State` id.
    pub fn id(self) -> u8 {
        match self {
            Self::Unconfigured => 1,
            Self::Inactive => 2,
            Self::Active => 3,
            Self::Finalized => 4,
        }
    }

    /// Its label, as rcl_lifecycle names it.
    pub fn label(self) -> &'static str {
        match self {
            Self::Unconfigured => "unconfigured",
            Self::Inactive => "inactive",
            Self::Active => "active",
            Self::Finalized => "finalized",
        }
    }

    /// As a message.
    pub fn message(self) -> LifecycleState {
        LifecycleState {
            id: self.id(),
            label: self.label().into(),
        }
    }
}

/// Every state `get_available_states` lists: the primary states with `unknown` (0), and the
/// transition states (10 to 15).
pub const ALL_STATES: [(u8, &str); 11] = [
    (0, "unknown"),
    (1, "unconfigured"),
    (2, "inactive"),
    (3, "active"),
    (4, "finalized"),
    (10, "configuring"),
    (11, "cleaningup"),
    (12, "shuttingdown"),
    (13, "activating"),
    (14, "deactivating"),
    (15, "errorprocessing"),
];

/// A transition a caller can request: its id and label, the primary state it starts from, the
/// transition state it passes through and the primary state it ends in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transition {
    pub id: u8,
    pub label: &'static str,
    pub start: State,
    /// The transition state's id and label.
    pub through: (u8, &'static str),
    pub goal: State,
}

/// rcl_lifecycle's default transitions that a caller requests (ids 1 to 7).
pub const TRANSITIONS: [Transition; 7] = [
    Transition {
        id: 1,
        label: "configure",
        start: State::Unconfigured,
        through: (10, "configuring"),
        goal: State::Inactive,
    },
    Transition {
        id: 2,
        label: "cleanup",
        start: State::Inactive,
        through: (11, "cleaningup"),
        goal: State::Unconfigured,
    },
    Transition {
        id: 3,
        label: "activate",
        start: State::Inactive,
        through: (13, "activating"),
        goal: State::Active,
    },
    Transition {
        id: 4,
        label: "deactivate",
        start: State::Active,
        through: (14, "deactivating"),
        goal: State::Inactive,
    },
    Transition {
        id: 5,
        label: "shutdown",
        start: State::Unconfigured,
        through: (12, "shuttingdown"),
        goal: State::Finalized,
    },
    Transition {
        id: 6,
        label: "shutdown",
        start: State::Inactive,
        through: (12, "shuttingdown"),
        goal: State::Finalized,
    },
    Transition {
        id: 7,
        label: "shutdown",
        start: State::Active,
        through: (12, "shuttingdown"),
        goal: State::Finalized,
    },
];

impl Transition {
    /// As `get_available_transitions` describes it: from the start state to the transition
    /// state.
    pub fn description(&self) -> TransitionDescription {
        TransitionDescription {
            transition: LifecycleTransition {
                id: self.id,
                label: self.label.into(),
            },
            start_state: self.start.message(),
            goal_state: LifecycleState {
                id: self.through.0,
                label: self.through.1.into(),
            },
        }
    }
}

/// The transitions available from `state`.
pub fn available(state: State) -> impl Iterator<Item = &'static Transition> {
    TRANSITIONS.iter().filter(move |t| t.start == state)
}

/// The state after a `change_state` request in `state`: a non-empty `label` names the
/// transition (its id is then not used, as rclcpp does: a command line leaves it 0), otherwise
/// `id` does. `None`: no such transition from `state` (the request fails, nothing changes).
pub fn change(state: State, id: u8, label: &str) -> Option<State> {
    available(state)
        .find(|t| {
            if label.is_empty() {
                t.id == id
            } else {
                t.label == label
            }
        })
        .map(|t| t.goal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standard_path_up_and_down() {
        let mut s = State::Unconfigured;
        for (label, want) in [
            ("configure", State::Inactive),
            ("activate", State::Active),
            ("deactivate", State::Inactive),
            ("cleanup", State::Unconfigured),
            ("configure", State::Inactive),
            ("activate", State::Active),
            ("shutdown", State::Finalized),
        ] {
            s = change(s, 0, label).unwrap_or_else(|| panic!("{label} from {s:?}"));
            assert_eq!(s, want, "{label}");
        }
        // Nothing leaves finalized.
        assert!(available(State::Finalized).next().is_none());
        for t in TRANSITIONS {
            assert_eq!(change(State::Finalized, t.id, ""), None);
        }
    }

    #[test]
    fn ids_work_without_a_label_and_only_from_their_start_state() {
        assert_eq!(change(State::Unconfigured, 1, ""), Some(State::Inactive));
        assert_eq!(change(State::Unconfigured, 3, ""), None);
        assert_eq!(change(State::Inactive, 3, ""), Some(State::Active));
        assert_eq!(change(State::Active, 1, ""), None);
        assert_eq!(change(State::Active, 7, ""), Some(State::Finalized));
        assert_eq!(change(State::Inactive, 7, ""), None);
        assert_eq!(change(State::Inactive, 99, ""), None);
        // A label wins over the id; an unknown label fails.
        assert_eq!(change(State::Inactive, 1, "activate"), Some(State::Active));
        assert_eq!(change(State::Inactive, 3, "configure"), None);
        assert_eq!(change(State::Inactive, 3, "Activate"), None);
    }

    #[test]
    fn available_transitions_as_rcl_lifecycle_lists_them() {
        let ids = |s| available(s).map(|t| t.id).collect::<Vec<_>>();
        assert_eq!(ids(State::Unconfigured), [1, 5]);
        assert_eq!(ids(State::Inactive), [2, 3, 6]);
        assert_eq!(ids(State::Active), [4, 7]);
        let d = TRANSITIONS[0].description();
        assert_eq!(
            (
                d.start_state.id,
                d.goal_state.id,
                d.goal_state.label.as_str()
            ),
            (1, 10, "configuring")
        );
    }
}
