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

use crate::msg::{Empty, PoseWithCovarianceStamped, TfMessage};

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
        let empty = ServiceTypeName::new("std_srvs", "Empty");
        let mut server = |n: &str| {
            node.create_server::<Empty, Empty>(
                config.service_mapping,
                &relative(n)?,
                &empty,
                service_qos.clone(),
                service_qos.clone(),
            )
            .map_err(|e| RosError(format!("service {n}: {e:?}")))
        };
        let global = server("reinitialize_global_localization")?;
        let nomotion = server("request_nomotion_update")?;
        Ok(Self {
            _node: node,
            amcl_pose,
            tf,
            initialpose,
            global,
            nomotion,
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
