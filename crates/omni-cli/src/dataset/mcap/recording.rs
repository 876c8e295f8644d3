//! A recording's channels, filled message by message from any storage: [`MessageSink`], what every storage
//! reader feeds, and [`Recording`], the sink behind the runs, which decodes every channel of a known type as
//! its messages come.
//!
//! A channel's first problem (an undecodable message, NaN, stamps going backwards, an unsupported encoding)
//! is kept with the channel and reported only if that channel is used, so a broken topic nobody asked for
//! does not stop the read.

use super::common::decode;
use super::joint_state::{self, JointSeries, JointState};
use super::odometry::{self, ODOM_FRAME, Odometry};
use super::pose_stamped::{self, NavSatFix, PointStamped, PoseStamped, PoseWithCovarianceStamped};
use super::poses::PoseSeries;
use super::tf::{self, TfMessage, TfPairs};
use super::twist::{self, Commands, TwistStamped};
use super::{McapOptions, ScanSink};

/// Schema encodings whose type names this reader knows. `ros2idl` names the same types with the same CDR
/// layout as `ros2msg` (rosbag2 writes it for types defined in `.idl` files).
const SCHEMA_ENCODINGS: [&str; 2] = ["ros2msg", "ros2idl"];
/// The only message encoding this reader decodes.
const MESSAGE_ENCODING: &str = "cdr";

/// The message types this reader decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum MsgType {
    JointState,
    PoseStamped,
    PoseWithCovarianceStamped,
    PointStamped,
    NavSatFix,
    Odometry,
    Tf,
    Twist,
    TwistStamped,
    Other,
}

impl MsgType {
    fn of(schema: &str) -> Self {
        match schema {
            joint_state::NAME => Self::JointState,
            pose_stamped::NAME => Self::PoseStamped,
            pose_stamped::WITH_COVARIANCE_NAME => Self::PoseWithCovarianceStamped,
            pose_stamped::POINT_NAME => Self::PointStamped,
            pose_stamped::NAV_SAT_FIX_NAME => Self::NavSatFix,
            odometry::NAME => Self::Odometry,
            tf::NAME => Self::Tf,
            twist::NAME => Self::Twist,
            twist::STAMPED_NAME => Self::TwistStamped,
            _ => Self::Other,
        }
    }
}

/// What a channel has gathered (the joints' series is the largest by far, but one per recording's wheel
/// topic: not worth a box on every access).
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub(super) enum Content {
    Joints(JointSeries),
    Poses(PoseSeries),
    Tf(TfPairs),
    Commands(Commands),
    Nothing,
}

/// One topic of the file.
#[derive(Debug)]
pub(super) struct Channel {
    pub(super) topic: String,
    /// Schema name, `""` without a schema.
    pub(super) schema: String,
    pub(super) msg_type: MsgType,
    /// Messages seen.
    pub(super) messages: usize,
    pub(super) content: Content,
    /// The first problem: the message index (`None` for the channel as a whole) and what is wrong. The
    /// channel takes nothing after it.
    pub(super) problem: Option<(Option<usize>, String)>,
    /// A NavSatFix channel's first fix (latitude, longitude in degrees, altitude in m): the origin of its
    /// local east-north-up positions.
    pub(super) geodetic_origin: Option<[f64; 3]>,
}

impl Channel {
    /// A topic as its storage declares it: schema (type) name, schema encoding, message encoding.
    fn new(topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> Self {
        let msg_type = MsgType::of(schema);
        let content = match msg_type {
            MsgType::JointState => Content::Joints(JointSeries::default()),
            MsgType::PoseStamped
            | MsgType::PoseWithCovarianceStamped
            | MsgType::PointStamped
            | MsgType::NavSatFix
            | MsgType::Odometry => Content::Poses(PoseSeries::default()),
            MsgType::Tf => Content::Tf(TfPairs::default()),
            MsgType::Twist | MsgType::TwistStamped => Content::Commands(Commands::default()),
            MsgType::Other => Content::Nothing,
        };
        let problem = (msg_type != MsgType::Other
            && !(SCHEMA_ENCODINGS.contains(&schema_encoding) && message_encoding == MESSAGE_ENCODING))
            .then(|| {
                (
                    None,
                    format!(
                        "schema encoding {schema_encoding:?} with message encoding {:?} is not supported \
                         (expected schema encoding \"ros2msg\" and message encoding \"cdr\", as rosbag2 records)",
                        message_encoding
                    ),
                )
            });
        Self {
            topic: topic.to_string(),
            schema: schema.to_string(),
            msg_type,
            messages: 0,
            content,
            problem,
            geodetic_origin: None,
        }
    }

    /// Takes the next message.
    fn take(&mut self, data: &[u8], log_time_ns: u64, wheel_joints: &[String]) {
        let index = self.messages;
        self.messages += 1;
        if self.problem.is_some() {
            return;
        }
        let result = match &mut self.content {
            Content::Joints(s) => decode::<JointState>(data)
                .and_then(|m| s.push(m, wheel_joints, i64::try_from(log_time_ns).unwrap_or(i64::MAX))),
            Content::Poses(s) => match self.msg_type {
                MsgType::PoseStamped => decode::<PoseStamped>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let p = &m.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::FIELDS)
                }),
                MsgType::PointStamped => decode::<PointStamped>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let (p, q) = (&m.point, &pose_stamped::NO_HEADING);
                    s.push(m.header.stamp.ns(), p, q, &pose_stamped::POINT_FIELDS)
                }),
                MsgType::NavSatFix => decode::<NavSatFix>(data).and_then(|m| {
                    if !m.has_fix() {
                        return Ok(());
                    }
                    let fix = m.geodetic()?;
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let origin = *self.geodetic_origin.get_or_insert(fix);
                    let p = NavSatFix::east_north_up(fix, origin);
                    s.push(m.header.stamp.ns(), &p, &pose_stamped::NO_HEADING, &pose_stamped::NAV_SAT_FIX_FIELDS)
                }),
                MsgType::PoseWithCovarianceStamped => decode::<PoseWithCovarianceStamped>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), None)?;
                    let p = &m.pose.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::WITH_COVARIANCE_FIELDS)
                }),
                _ => decode::<Odometry>(data).and_then(|m| {
                    s.check_frame(m.header.frame_id.frame(), Some(m.child_frame_id.frame()))?;
                    let p = &m.pose.pose;
                    s.push(m.header.stamp.ns(), &p.position, &p.orientation, &pose_stamped::WITH_COVARIANCE_FIELDS)
                }),
            },
            Content::Tf(pairs) => decode::<TfMessage>(data).map(|m| pairs.push(index, &m)),
            Content::Commands(c) => match self.msg_type {
                MsgType::TwistStamped => {
                    decode::<TwistStamped>(data).and_then(|m| c.push(m.header.stamp.ns(), &m.twist))
                }
                _ => decode(data).and_then(|t| c.push(i64::try_from(log_time_ns).unwrap_or(i64::MAX), &t)),
            },
            Content::Nothing => Ok(()),
        };
        if let Err(e) = result {
            self.problem = Some((Some(index), e));
        }
    }

    /// The frame of the first pose, for pose channels.
    pub(super) fn frame(&self) -> Option<&str> {
        match &self.content {
            Content::Poses(s) => s.frame.as_deref(),
            _ => None,
        }
    }

    /// Whether this is the robot's own wheel odometry (REP-105: Odometry in frame `odom`).
    pub(super) fn is_wheel_odometry(&self) -> bool {
        self.msg_type == MsgType::Odometry && self.frame() == Some(ODOM_FRAME)
    }

    /// `/topic (type, N messages, frame "f")`.
    pub(super) fn describe(&self) -> String {
        let schema = if self.schema.is_empty() { "no schema" } else { &self.schema };
        let plural = if self.messages == 1 { "" } else { "s" };
        let mut s = format!("{} ({schema}, {} message{plural}", self.topic, self.messages);
        if let Some(f) = self.frame() {
            s.push_str(&format!(", frame {f:?}"));
        }
        if self.is_wheel_odometry() {
            s.push_str(": the robot's own odometry");
        }
        s.push(')');
        s
    }

    /// `/topic (type, frame "f")`, for lists of candidates.
    pub(super) fn candidate(&self) -> String {
        match self.frame() {
            Some(f) => format!("{} ({}, frame {f:?})", self.topic, self.schema),
            None => format!("{} ({})", self.topic, self.schema),
        }
    }
}

/// Where the storage readers (MCAP files, rosbag2 sqlite3 files) put a recording's topics and messages:
/// [`Recording`] (the runs) or an inventory of the topics (`omnical init`, [`super::inspect`]).
/// A message's payload as its decoder needs it: as recorded, or, for rosbag2's per-message compression
/// (`zstd_messages`), zstd-decompressed; the error says why it does not decompress. Every sink reads
/// payloads through it, and only those of the topics it reads (decompressing a camera's images for nothing
/// would cost more than the whole read).
pub(crate) fn payload(zstd_messages: bool, data: &[u8]) -> Result<std::borrow::Cow<'_, [u8]>, String> {
    if !zstd_messages {
        return Ok(std::borrow::Cow::Borrowed(data));
    }
    zstd::stream::decode_all(data)
        .map(std::borrow::Cow::Owned)
        .map_err(|e| format!("the zstd-compressed message does not decompress: {e}"))
}

pub(crate) trait MessageSink {
    /// The channel of `topic`, declared on its first sight (a later declaration of the same topic, in another
    /// split file, keeps the first one's type).
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize;
    /// Takes the next message of channel `i` (an index from [`Self::channel`]), logged at `log_time_ns` (ns
    /// since the epoch).
    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64);
}

/// The channels of one recording, filled message by message from any storage (MCAP files, rosbag2 sqlite3
/// files, several split files of one recording): the one message pipeline behind every reader. Topics are
/// matched by name, so the split files of a recording feed the same channels.
pub(crate) struct Recording {
    wheel_joints: Vec<String>,
    pub(super) channels: Vec<Channel>,
    /// Every message payload is zstd-compressed on its own (rosbag2's `compression_mode: MESSAGE`).
    pub(crate) zstd_messages: bool,
    /// The lidar's scans gathered in the same pass ([`McapOptions::scan_topic`]), and the scan sink's
    /// index of each channel.
    scans: Option<(ScanSink, Vec<usize>)>,
}

impl Recording {
    /// An empty recording whose JointState topics are read for these wheel joints (in wheel order).
    pub(crate) fn new(wheel_joints: &[String]) -> Self {
        Self { wheel_joints: wheel_joints.to_vec(), channels: Vec::new(), zstd_messages: false, scans: None }
    }

    /// An empty recording read with `opts`: its wheel joints, and its scans when it names a scan topic
    /// (the lidar's mount looked up from its base frame), so that one pass reads both.
    pub(crate) fn for_read(opts: &McapOptions) -> Self {
        let scans = opts
            .scan_topic
            .as_deref()
            .map(|topic| (ScanSink::new(topic, false).with_base_frame(opts.base_frame.as_deref()), Vec::new()));
        Self { scans, ..Self::new(&opts.wheel_joints) }
    }

    /// The channels, and the scans' sink when they were gathered.
    pub(super) fn into_parts(self) -> (Vec<Channel>, Option<ScanSink>) {
        (self.channels, self.scans.map(|(s, _)| s))
    }

    /// Messages taken on `topic` (`None`: no such topic).
    pub(crate) fn messages_on(&self, topic: &str) -> Option<usize> {
        self.channels.iter().find(|c| c.topic == topic).map(|c| c.messages)
    }
}

impl MessageSink for Recording {
    fn channel(&mut self, topic: &str, schema: &str, schema_encoding: &str, message_encoding: &str) -> usize {
        match self.channels.iter().position(|c| c.topic == topic) {
            Some(i) => i,
            None => {
                self.channels.push(Channel::new(topic, schema, schema_encoding, message_encoding));
                if let Some((sink, index)) = &mut self.scans {
                    sink.zstd_messages = self.zstd_messages;
                    index.push(sink.channel(topic, schema, schema_encoding, message_encoding));
                }
                self.channels.len() - 1
            }
        }
    }

    fn message(&mut self, i: usize, data: &[u8], log_time_ns: u64) {
        if let Some((sink, index)) = &mut self.scans {
            sink.message(index[i], data, log_time_ns);
        }
        let c = &mut self.channels[i];
        if self.zstd_messages && c.msg_type != MsgType::Other && c.problem.is_none() {
            match payload(true, data) {
                Ok(plain) => return c.take(&plain, log_time_ns, &self.wheel_joints),
                Err(e) => {
                    c.problem = Some((Some(c.messages), e));
                    c.messages += 1;
                    return;
                }
            }
        }
        c.take(data, log_time_ns, &self.wheel_joints);
    }
}
