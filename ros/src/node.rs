//! The node on the ROS 2 graph: a zenoh session as rmw_zenoh opens one (a peer connected to the
//! graph's router, multicast scouting off), a liveliness token for the node and for each of its
//! publishers and subscriptions, and one thread that takes every message in the order it came:
//! frames into the touch ([`Touches`]), contact and reset, and the answers out, each with the
//! attachment rmw_zenoh readers expect (sequence number, source time, GID).

use std::sync::mpsc;
use std::time::{SystemTime, UNIX_EPOCH};

use pvt3_messages::{decode, Kind, Stamp};
use zenoh::Wait;

use crate::args::Args;
use crate::graph::{self, Entity, Qos, Topic};
use crate::outgoing::{self, Level};
use crate::touch::{Boundary, Touches, TouchesError};

/// Why the node could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// A parameter's value is wrong.
    #[error("{0}")]
    Parameter(String),
    /// The file did not load.
    #[error(transparent)]
    Model(#[from] pvt3_runtime::Error),
    /// zenoh refused (no router, a key it cannot take).
    #[error("zenoh: {0}")]
    Zenoh(String),
}

impl From<TouchesError> for NodeError {
    fn from(e: TouchesError) -> Self {
        match e {
            TouchesError::Runtime(e) => Self::Model(e),
            TouchesError::Boundary(why) => Self::Parameter(why),
        }
    }
}

fn zenoh_error(e: impl std::fmt::Display) -> NodeError {
    NodeError::Zenoh(e.to_string())
}

/// A message as it arrived: its key expression (which names its type), its CDR, and its
/// publisher's GID where its attachment gives one.
struct Received {
    key: String,
    data: Vec<u8>,
    source: Option<[u8; 16]>,
}

/// What arrives on the node's subscriptions, in order.
enum Event {
    Frame(Received),
    Contact(Received),
    Reset,
    /// A publisher of the frames' topic left the graph (its token's GID).
    PublisherGone([u8; 16]),
}

/// A publisher and what rmw_zenoh puts beside each message.
struct Out {
    publisher: zenoh::pubsub::Publisher<'static>,
    gid: [u8; 16],
    sequence: i64,
}

impl Out {
    fn put(&mut self, message: Vec<u8>) -> Result<(), NodeError> {
        self.sequence += 1;
        let mut attachment = zenoh_ext::ZSerializer::new();
        attachment.serialize(self.sequence);
        attachment.serialize(now_nanos());
        attachment.serialize(self.gid);
        self.publisher.put(message).attachment(attachment.finish()).wait().map_err(zenoh_error)
    }
}

fn now_nanos() -> i64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos() as i64)
}

fn now() -> Stamp {
    let ns = now_nanos();
    Stamp { sec: (ns / 1_000_000_000) as i32, nanosec: (ns % 1_000_000_000) as u32 }
}

/// The node, joined to the graph.
pub struct Node {
    args: Args,
    session: zenoh::Session,
    touches: Touches,
    events: mpsc::Receiver<Event>,
    classification: Out,
    status: Out,
    rosout: Out,
    /// Kept for as long as the node serves: its subscribers and every entity's token.
    _subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    _tokens: Vec<zenoh::liveliness::LivelinessToken>,
    entities: usize,
}

impl Node {
    /// Loads the file, opens the session and declares the node's endpoints.
    pub fn start(args: Args) -> Result<Self, NodeError> {
        let classifier = pvt3_runtime::Classifier::load(args.parameter("model"))?;
        let boundary = match args.parameter("touch") {
            "frames" => Boundary::Frames,
            "contact" => Boundary::Contact,
            "moving" => {
                let recording = args.parameter("recording");
                let frames =
                    recording.parse().map_err(|_| NodeError::Parameter(format!("recording:={recording}: expected a count of frames")))?;
                Boundary::Moving(frames)
            }
            other => return Err(NodeError::Parameter(format!("touch:={other}: expected frames, contact or moving"))),
        };
        let early_stop = match args.parameter("early_stop") {
            "true" => true,
            "false" => false,
            other => return Err(NodeError::Parameter(format!("early_stop:={other}: expected true or false"))),
        };
        let camera = classifier.camera().is_some();
        let touches = Touches::new(classifier, boundary, early_stop)?;
        let mut config = zenoh::Config::default();
        let router = args.parameter("router");
        for (key, value) in [
            ("mode", "\"peer\"".to_string()),
            ("connect/endpoints", format!("[\"{router}\"]")),
            ("listen/endpoints", "[\"tcp/localhost:0\"]".to_string()),
            ("scouting/multicast/enabled", "false".to_string()),
        ] {
            config.insert_json5(key, &value).map_err(|e| NodeError::Parameter(format!("router:={router}: {e}")))?;
        }
        let session = zenoh::open(config).wait().map_err(zenoh_error)?;
        let (sender, events) = mpsc::channel();
        let mut node = NodeBuilder { args: &args, session: &session, sender, subscribers: Vec::new(), tokens: Vec::new(), entities: 0 };
        node.token(graph::Kind::Node, None)?;
        let frames_type = if camera { "sensor_msgs/msg/Image" } else { "std_msgs/msg/Float32MultiArray" };
        node.subscribe("frames", frames_type, Event::Frame)?;
        node.subscribe("contact", "std_msgs/msg/Bool", Event::Contact)?;
        node.subscribe("reset", "std_msgs/msg/Empty", |_| Event::Reset)?;
        node.watch_publishers("frames")?;
        let classification = node.publisher("classification", "vision_msgs/msg/Classification")?;
        let status = node.publisher("touch_status", "diagnostic_msgs/msg/DiagnosticStatus")?;
        let rosout = node.publisher("/rosout", "rcl_interfaces/msg/Log")?;
        let NodeBuilder { subscribers, tokens, entities, .. } = node;
        Ok(Self { args, session, touches, events, classification, status, rosout, _subscribers: subscribers, _tokens: tokens, entities })
    }

    /// The zenoh session's id, as the node's tokens give it.
    pub fn session_id(&self) -> String {
        self.session.zid().to_string()
    }

    /// Entities declared on the graph (the node, its subscriptions and publishers).
    pub fn entities(&self) -> usize {
        self.entities
    }

    /// Serves until the session closes: every message in turn, a refused one said on `/rosout`
    /// and stderr, the node going on.
    pub fn serve(mut self) -> Result<(), NodeError> {
        let name = self.args.node.name.clone();
        self.log(Level::Info, &format!("classifying {} with {}", self.args.topic("frames"), self.args.parameter("model")))?;
        while let Ok(event) = self.events.recv() {
            let result = match event {
                Event::Frame(received) => self.frame(&received),
                Event::Contact(received) => match pvt3_messages::cdr::Reader::new(&received.data).and_then(|mut r| r.read::<u8>("data")) {
                    Ok(on) => self.touches.contact(on != 0).map_err(|e| e.0),
                    Err(e) => Err(format!("{}: {e}", self.args.topic("contact"))),
                },
                Event::Reset => {
                    self.touches.reset();
                    Ok(None)
                }
                Event::PublisherGone(gid) => self.touches.publisher_gone(gid).map_or(Ok(None), Err),
            };
            match result {
                Ok(Some(answer)) => self.publish(answer)?,
                Ok(None) => {}
                Err(why) => {
                    eprintln!("[{name}] {why}");
                    self.log(Level::Warn, &why)?;
                }
            }
        }
        Ok(())
    }

    /// A frame message (its type the key's part before the hash).
    fn frame(&mut self, received: &Received) -> Result<Option<crate::touch::Answer>, String> {
        let topic = self.args.topic("frames");
        let type_name = received.key.rsplit('/').nth(1).unwrap_or_default();
        let kind = Kind::of(type_name).ok_or_else(|| format!("{topic}: a message of type {type_name}, which pvt3 does not read"))?;
        let decoded = decode(kind, &received.data).map_err(|e| format!("{topic}: {e}"))?;
        self.touches.frame(decoded, now(), received.source).map_err(|e| format!("{topic}: {e}"))
    }

    fn publish(&mut self, answer: crate::touch::Answer) -> Result<(), NodeError> {
        let classes = self.touches.classifier().classes().to_vec();
        let frame_id = self.args.parameter("frame_id").to_string();
        self.classification.put(outgoing::classification(answer.stamp, &frame_id, &classes, &answer.prediction.probabilities))?;
        self.status.put(outgoing::status(&self.args.node.name, &answer.status))
    }

    fn log(&mut self, level: Level, text: &str) -> Result<(), NodeError> {
        let name = self.args.node.name.clone();
        self.rosout.put(outgoing::log(now(), level, &name, text))
    }
}

/// Declares the node's entities one after another, numbered as rmw_zenoh numbers them.
struct NodeBuilder<'a> {
    args: &'a Args,
    session: &'a zenoh::Session,
    sender: mpsc::Sender<Event>,
    subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    tokens: Vec<zenoh::liveliness::LivelinessToken>,
    entities: usize,
}

/// The QoS the node's endpoints declare: reliable, ten kept (rclcpp's default).
const QOS: Qos = Qos { best_effort: false, depth: 10 };

impl NodeBuilder<'_> {
    fn token(&mut self, kind: graph::Kind, topic: Option<&Topic>) -> Result<Entity, NodeError> {
        let entity = Entity::new(&self.session.zid().to_string(), 0, self.entities, kind, &self.args.node, topic);
        self.entities += 1;
        let token = self.session.liveliness().declare_token(entity.token.clone()).wait().map_err(zenoh_error)?;
        self.tokens.push(token);
        Ok(entity)
    }

    fn topic(&self, name: &str, type_name: &str) -> Result<Topic, NodeError> {
        Topic::new(&self.args.topic(name), type_name, QOS).map_err(|e| NodeError::Parameter(e.to_string()))
    }

    /// Subscribes to topic `name` of any type (its messages' keys say which), declaring it as
    /// `type_name`.
    fn subscribe(&mut self, name: &str, type_name: &str, event: fn(Received) -> Event) -> Result<(), NodeError> {
        let topic = self.topic(name, type_name)?;
        let key = format!("{}/{}/*/*", self.args.node.domain, topic.name.trim_matches('/'));
        let sender = self.sender.clone();
        let subscriber = self
            .session
            .declare_subscriber(key)
            .callback(move |sample| {
                let source = sample.attachment().and_then(|a| zenoh_ext::z_deserialize::<(i64, i64, [u8; 16])>(a).ok()).map(|a| a.2);
                let (key, data) = (sample.key_expr().as_str().to_string(), sample.payload().to_bytes().into_owned());
                let _ = sender.send(event(Received { key, data, source }));
            })
            .wait()
            .map_err(zenoh_error)?;
        self.subscribers.push(subscriber);
        // Declared once the subscriber is: a publisher that waits for the token is heard.
        self.token(graph::Kind::Subscription, Some(&topic))?;
        Ok(())
    }

    /// Watches the liveliness tokens of the publishers of topic `name`: one that leaves is
    /// told to the touch by its GID (the XXH3-128 of its token, as rmw_zenoh derives it).
    fn watch_publishers(&mut self, name: &str) -> Result<(), NodeError> {
        let topic = self.args.topic(name).replace('/', "%");
        let key = format!("@ros2_lv/{}/*/*/*/MP/*/*/*/{topic}/**", self.args.node.domain);
        let sender = self.sender.clone();
        let watch = self
            .session
            .liveliness()
            .declare_subscriber(key)
            .callback(move |sample| {
                if sample.kind() == zenoh::sample::SampleKind::Delete {
                    let _ = sender.send(Event::PublisherGone(graph::gid(sample.key_expr().as_str())));
                }
            })
            .wait()
            .map_err(zenoh_error)?;
        self.subscribers.push(watch);
        Ok(())
    }

    fn publisher(&mut self, name: &str, type_name: &str) -> Result<Out, NodeError> {
        let topic = self.topic(name, type_name)?;
        let entity = self.token(graph::Kind::Publisher, Some(&topic))?;
        // Blocking rather than dropping when the link is busy: an answer is one message a touch,
        // and none may be lost. Express: sent at once, never held in a batch for what may follow
        // (zenoh's transmission task otherwise backs off for up to its batching time, 1 ms, on a
        // timer of 1 ms resolution).
        let key = topic.key_expr(self.args.node.domain);
        let publisher = self
            .session
            .declare_publisher(key)
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .express(true)
            .wait()
            .map_err(zenoh_error)?;
        Ok(Out { publisher, gid: entity.gid, sequence: 0 })
    }
}
