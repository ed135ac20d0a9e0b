//! The bridge's ROS 2 node (ros2-client over RustDDS; no ROS installation): nav2_amcl's
//! topics, QoS and services.
//!
//! | name | kind | type | QoS |
//! |---|---|---|---|
//! | `amcl_pose` | publisher | geometry_msgs/PoseWithCovarianceStamped | reliable, transient local, depth 1 |
//! | `/tf` | publisher | tf2_msgs/TFMessage | reliable, volatile, depth 100 |
//! | `initialpose` | subscription | geometry_msgs/PoseWithCovarianceStamped | reliable, volatile, depth 10 |
//! | `reinitialize_global_localization` | service | std_srvs/Empty | services' default |
//! | `request_nomotion_update` | service | std_srvs/Empty | services' default |
//! | `amcl/get_state`, `amcl/change_state`, `amcl/get_available_states`, `amcl/get_available_transitions` | services | lifecycle_msgs | services' default |
//!
//! With `loopback_only`, the DDS participant uses only 127.0.0.1: multicast is joined and sent
//! on no other interface, only the loopback address is advertised in discovery, and peers on
//! the same host are found by unicast to the well-known discovery ports of 127.0.0.1.

use std::net::IpAddr;

use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile, Server,
    ServiceMapping, ServiceTypeName, Subscription,
};

use crate::lifecycle::{self, State};
use crate::msg::{
    ChangeStateRequest, ChangeStateResponse, Empty, GetAvailableStatesResponse,
    GetAvailableTransitionsResponse, GetStateResponse, LifecycleState, PoseWithCovarianceStamped,
    TfMessage,
};

/// How the node is set up.
#[derive(Clone, Debug)]
pub struct NodeConfig {
    /// The DDS domain (`ROS_DOMAIN_ID`).
    pub domain_id: u16,
    /// Node name and namespace (nav2's: `amcl`, `/`).
    pub name: String,
    pub namespace: String,
    /// Use 127.0.0.1 only.
    pub loopback_only: bool,
    /// The services' mapping onto DDS: it depends on the peers' RMW (Cyclone DDS's differs).
    pub service_mapping: ServiceMapping,
}

/// A service call that reached the bridge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServiceCall {
    ReinitializeGlobalLocalization,
    RequestNomotionUpdate,
}

/// The node and its endpoints.
pub struct RosNode {
    // Kept alive: dropping the node ends its participant.
    _node: Node,
    amcl_pose: Publisher<PoseWithCovarianceStamped>,
    tf: Publisher<TfMessage>,
    initialpose: Subscription<PoseWithCovarianceStamped>,
    global: Server<Empty, Empty>,
    nomotion: Server<Empty, Empty>,
    get_state: Server<Empty, GetStateResponse>,
    change_state: Server<ChangeStateRequest, ChangeStateResponse>,
    get_available_states: Server<Empty, GetAvailableStatesResponse>,
    get_available_transitions: Server<Empty, GetAvailableTransitionsResponse>,
}

/// A lifecycle transition a caller requested and the bridge made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Changed {
    pub from: State,
    pub to: State,
}

/// A ROS 2 side that could not be set up or failed.
#[derive(Debug)]
pub struct RosError(pub String);

impl std::fmt::Display for RosError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ROS 2: {}", self.0)
    }
}

impl std::error::Error for RosError {}

/// A message not published.
#[derive(Debug)]
pub enum PublishError<M> {
    /// The writer's window is full (a reliable reader has not acknowledged yet): the message
    /// is handed back to be retried ([`crate::outbox::Outbox`]).
    WouldBlock(Box<M>),
    /// Any other failure.
    Failed(RosError),
}

fn publish_error<M>(what: &str, e: ros2_client::WriteError<M>) -> PublishError<M> {
    match e {
        ros2_client::WriteError::WouldBlock { data } => PublishError::WouldBlock(Box::new(data)),
        other => PublishError::Failed(RosError(format!(
            "{what}: {}",
            match other {
                ros2_client::WriteError::Serialization { reason, .. }
                | ros2_client::WriteError::Poisoned { reason, .. }
                | ros2_client::WriteError::Internal { reason }
                | ros2_client::WriteError::Middleware { reason, .. } => reason,
                ros2_client::WriteError::Io(e) => e.to_string(),
                ros2_client::WriteError::WouldBlock { .. } => "would block".into(),
            }
        ))),
    }
}

fn err<E: std::fmt::Debug>(what: &str) -> impl FnOnce(E) -> RosError + '_ {
    move |e| RosError(format!("{what}: {e:?}"))
}

/// An absolute name, `/base` or `/ns/base` (nav2_amcl's names are relative to its node's
/// namespace, `/` by default).
/// A server named `name` of the service type `srv`, with `qos` for its requests and replies.
fn serve<Req, Resp>(
    node: &mut Node,
    mapping: ServiceMapping,
    name: &Name,
    srv: &ServiceTypeName,
    qos: &QosProfile,
) -> Result<Server<Req, Resp>, RosError>
where
    Req: ros2_client::Message + Clone + 'static,
    Resp: ros2_client::Message + 'static,
{
    node.create_server(mapping, name, srv, qos.clone(), qos.clone())
        .map_err(|e| RosError(format!("service {name}: {e:?}")))
}

fn name(n: &str) -> Result<Name, RosError> {
    let (ns, base) = match n.rsplit_once('/') {
        Some(("", base)) => ("/", base),
        Some((ns, base)) => (ns, base),
        None => ("/", n),
    };
    Name::new(ns, base).map_err(err(n))
}

impl RosNode {
    /// Creates the participant, the node and its endpoints.
    pub fn new(config: &NodeConfig) -> Result<Self, RosError> {
        let mut builder = rustdds::DomainParticipantBuilder::new(config.domain_id);
        if config.loopback_only {
            builder = builder
                .with_only_networks([IpAddr::from([127, 0, 0, 1])])
                .same_host_loopback(true);
        }
        let participant = builder.build().map_err(err("the DDS participant"))?;
        let context = Context::from_domain_participant(participant).map_err(err("the context"))?;
        let node_name =
            NodeName::new(&config.namespace, &config.name).map_err(err("the node name"))?;
        let mut node = context
            .new_node(node_name, NodeOptions::new())
            .map_err(err("the node"))?;
        // The publishers never wait for a full window: the write is refused at once and the
        // bridge's outbox retries the newest message (crate::outbox).
        let latched = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 });
        let tf_qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Fail)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 100 });
        let sub_qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::DEFAULT)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        // nav2_amcl's names are relative to its namespace; `/tf` is absolute.
        let ns = config.namespace.trim_end_matches('/');
        let relative = |n: &str| name(&format!("{ns}/{n}"));
        let pose_type = || MessageTypeName::new("geometry_msgs", "PoseWithCovarianceStamped");
        let topic = node
            .create_topic(&relative("amcl_pose")?, pose_type(), &latched)
            .map_err(err("topic amcl_pose"))?;
        let amcl_pose = node
            .create_publisher(&topic, None)
            .map_err(err("publisher amcl_pose"))?;
        let topic = node
            .create_topic(
                &name("/tf")?,
                MessageTypeName::new("tf2_msgs", "TFMessage"),
                &tf_qos,
            )
            .map_err(err("topic /tf"))?;
        let tf = node
            .create_publisher(&topic, None)
            .map_err(err("publisher /tf"))?;
        let topic = node
            .create_topic(&relative("initialpose")?, pose_type(), &sub_qos)
            .map_err(err("topic initialpose"))?;
        let initialpose = node
            .create_subscription(&topic, None)
            .map_err(err("subscription initialpose"))?;
        let service_qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::DEFAULT)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        let mapping = config.service_mapping;
        let empty = ServiceTypeName::new("std_srvs", "Empty");
        let global = serve(
            &mut node,
            mapping,
            &relative("reinitialize_global_localization")?,
            &empty,
            &service_qos,
        )?;
        let nomotion = serve(
            &mut node,
            mapping,
            &relative("request_nomotion_update")?,
            &empty,
            &service_qos,
        )?;
        // The lifecycle services are the node's own: `<node>/get_state` and so on.
        let node_name = &config.name;
        let own = |n: &str| relative(&format!("{node_name}/{n}"));
        let lifecycle_type = |srv: &str| ServiceTypeName::new("lifecycle_msgs", srv);
        let get_state = serve(
            &mut node,
            mapping,
            &own("get_state")?,
            &lifecycle_type("GetState"),
            &service_qos,
        )?;
        let change_state = serve(
            &mut node,
            mapping,
            &own("change_state")?,
            &lifecycle_type("ChangeState"),
            &service_qos,
        )?;
        let get_available_states = serve(
            &mut node,
            mapping,
            &own("get_available_states")?,
            &lifecycle_type("GetAvailableStates"),
            &service_qos,
        )?;
        let get_available_transitions = serve(
            &mut node,
            mapping,
            &own("get_available_transitions")?,
            &lifecycle_type("GetAvailableTransitions"),
            &service_qos,
        )?;
        Ok(Self {
            _node: node,
            amcl_pose,
            tf,
            initialpose,
            global,
            nomotion,
            get_state,
            change_state,
            get_available_states,
            get_available_transitions,
        })
    }

    /// Publishes an estimate; a full window hands it back.
    pub fn publish_pose(
        &self,
        m: PoseWithCovarianceStamped,
    ) -> Result<(), PublishError<PoseWithCovarianceStamped>> {
        self.amcl_pose
            .publish(m)
            .map_err(|e| publish_error("publishing amcl_pose", e))
    }

    /// Publishes a `/tf` message; a full window hands it back.
    pub fn publish_tf(&self, m: TfMessage) -> Result<(), PublishError<TfMessage>> {
        self.tf
            .publish(m)
            .map_err(|e| publish_error("publishing /tf", e))
    }

    /// The `initialpose` messages that arrived; a sample that could not be read is an `Err`
    /// (counted by the caller; the subscription goes on).
    pub fn initial_poses(&self) -> Vec<Result<PoseWithCovarianceStamped, RosError>> {
        let mut out = Vec::new();
        loop {
            match self.initialpose.take() {
                Ok(Some((m, _))) => out.push(Ok(m)),
                Ok(None) => return out,
                Err(e) => {
                    out.push(Err(RosError(format!("reading initialpose: {e:?}"))));
                    return out;
                }
            }
        }
    }

    /// Answers the lifecycle requests that arrived: the state, the available states and
    /// transitions, and `change_state`, which moves `state` when the transition exists from it
    /// ([`lifecycle::change`]). Returns the transitions made; a request that could not be read
    /// or answered is an `Err` (the bridge goes on).
    pub fn lifecycle_calls(&mut self, state: &mut State) -> Vec<Result<Changed, RosError>> {
        let mut out = Vec::new();
        let failed = |what: &str, e: &dyn std::fmt::Debug| RosError(format!("{what}: {e:?}"));
        while let Some(r) = self.get_state.receive_request().transpose() {
            match r {
                Ok((id, _)) => {
                    let a = GetStateResponse {
                        current_state: state.message(),
                    };
                    if let Err(e) = self.get_state.send_response(id, a) {
                        out.push(Err(failed("answering get_state", &e)));
                    }
                }
                Err(e) => {
                    out.push(Err(failed("reading a get_state request", &e)));
                    break;
                }
            }
        }
        while let Some(r) = self.get_available_states.receive_request().transpose() {
            match r {
                Ok((id, _)) => {
                    let a = GetAvailableStatesResponse {
                        available_states: lifecycle::ALL_STATES
                            .iter()
                            .map(|(id, label)| LifecycleState {
                                id: *id,
                                label: (*label).into(),
                            })
                            .collect(),
                    };
                    if let Err(e) = self.get_available_states.send_response(id, a) {
                        out.push(Err(failed("answering get_available_states", &e)));
                    }
                }
                Err(e) => {
                    out.push(Err(failed("reading a get_available_states request", &e)));
                    break;
                }
            }
        }
        while let Some(r) = self.get_available_transitions.receive_request().transpose() {
            match r {
                Ok((id, _)) => {
                    let a = GetAvailableTransitionsResponse {
                        available_transitions: lifecycle::available(*state)
                            .map(lifecycle::Transition::description)
                            .collect(),
                    };
                    if let Err(e) = self.get_available_transitions.send_response(id, a) {
                        out.push(Err(failed("answering get_available_transitions", &e)));
                    }
                }
                Err(e) => {
                    out.push(Err(failed(
                        "reading a get_available_transitions request",
                        &e,
                    )));
                    break;
                }
            }
        }
        while let Some(r) = self.change_state.receive_request().transpose() {
            match r {
                Ok((id, req)) => {
                    let from = *state;
                    let to = lifecycle::change(from, req.transition.id, &req.transition.label);
                    if let Some(to) = to {
                        *state = to;
                        out.push(Ok(Changed { from, to }));
                    }
                    let a = ChangeStateResponse {
                        success: to.is_some(),
                    };
                    if let Err(e) = self.change_state.send_response(id, a) {
                        out.push(Err(failed("answering change_state", &e)));
                    }
                }
                Err(e) => {
                    out.push(Err(failed("reading a change_state request", &e)));
                    break;
                }
            }
        }
        out
    }

    /// The service calls that arrived, each already answered (std_srvs/Empty carries nothing
    /// back; nav2_amcl answers at once too).
    pub fn service_calls(&mut self) -> Vec<Result<ServiceCall, RosError>> {
        let mut out = Vec::new();
        for (server, call) in [
            (
                &mut self.global,
                ServiceCall::ReinitializeGlobalLocalization,
            ),
            (&mut self.nomotion, ServiceCall::RequestNomotionUpdate),
        ] {
            loop {
                match server.receive_request() {
                    Ok(Some((id, _))) => {
                        let answered = server
                            .send_response(id, Empty::default())
                            .map_err(err("answering a service call"));
                        out.push(answered.map(|()| call));
                    }
                    Ok(None) => break,
                    Err(e) => {
                        out.push(Err(RosError(format!("reading a service request: {e:?}"))));
                        break;
                    }
                }
            }
        }
        out
    }
}
