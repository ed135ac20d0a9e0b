//! What the bridge's integration tests share: a ROS 2 node whose DDS stays on 127.0.0.1, a
//! reliable subscription to one topic, and a link frame's bytes.

// Each test file uses part of this.
#![allow(dead_code)]

use std::net::IpAddr;

use beamfield::link::{Encoder, Message, MAX_WIRE_LEN};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, QosProfile, Subscription,
};

/// A node named `/name` on DDS domain `domain`, talking on the loopback interface only.
pub fn loopback_node(domain: u16, name: &str) -> Node {
    let participant = rustdds::DomainParticipantBuilder::new(domain)
        .with_only_networks([IpAddr::from([127, 0, 0, 1])])
        .same_host_loopback(true)
        .build()
        .unwrap();
    let context = Context::from_domain_participant(participant).unwrap();
    context
        .new_node(NodeName::new("/", name).unwrap(), NodeOptions::new())
        .unwrap()
}

/// A reliable, volatile subscription to the absolute topic `/topic` of the message type
/// `package/type_name`, keeping the last `depth` samples.
pub fn subscribe<M: serde::de::DeserializeOwned + 'static>(
    node: &mut Node,
    topic: &str,
    package: &str,
    type_name: &str,
    depth: usize,
) -> Subscription<M> {
    let qos = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth });
    let topic = node
        .create_topic(
            &Name::new("/", topic).unwrap(),
            MessageTypeName::new(package, type_name),
            &qos,
        )
        .unwrap();
    node.create_subscription::<M>(&topic, None).unwrap()
}

/// The bytes of `m` as the device sends it.
pub fn frame(enc: &mut Encoder, m: &Message) -> Vec<u8> {
    let mut w = [0u8; MAX_WIRE_LEN];
    let n = enc.encode(m, &mut w).unwrap();
    w[..n].to_vec()
}
