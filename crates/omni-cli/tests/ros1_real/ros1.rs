//! A ROS 1 bag of format 2.0, written as `rosbag record` lays it out: the bag header padded to 4096 bytes,
//! one uncompressed chunk holding the connections and the messages, then the index (the connections again).

/// One record: its header fields and its data.
fn record(fields: &[(&str, Vec<u8>)], data: &[u8]) -> Vec<u8> {
    let mut header = Vec::new();
    for (name, value) in fields {
        header.extend(((name.len() + 1 + value.len()) as u32).to_le_bytes());
        header.extend(name.as_bytes());
        header.push(b'=');
        header.extend(value);
    }
    let mut out = (header.len() as u32).to_le_bytes().to_vec();
    out.extend(header);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
    out
}

fn time(ns: u64) -> Vec<u8> {
    let mut t = ((ns / 1_000_000_000) as u32).to_le_bytes().to_vec();
    t.extend(((ns % 1_000_000_000) as u32).to_le_bytes());
    t
}

fn connection(id: u32, topic: &str, msg_type: &str) -> Vec<u8> {
    let fields: [(&str, Vec<u8>); 4] = [
        ("topic", topic.into()),
        ("type", msg_type.into()),
        ("md5sum", vec![b'0'; 32]),
        ("message_definition", b"# written by the omnical tests".to_vec()),
    ];
    let mut data = Vec::new();
    for (name, value) in fields {
        data.extend(((name.len() + 1 + value.len()) as u32).to_le_bytes());
        data.extend(name.as_bytes());
        data.push(b'=');
        data.extend(value);
    }
    record(&[("op", vec![0x07]), ("conn", id.to_le_bytes().to_vec()), ("topic", topic.into())], &data)
}

/// The bag's bytes: `topics` (name, ROS 1 type) and `messages` (topic index, log time ns, ROS 1 bytes).
pub fn bytes(topics: &[(&str, &str)], messages: &[(usize, u64, Vec<u8>)]) -> Vec<u8> {
    let mut chunk = Vec::new();
    for (i, (topic, msg_type)) in topics.iter().enumerate() {
        chunk.extend(connection(i as u32, topic, msg_type));
    }
    for (i, ns, data) in messages {
        chunk.extend(record(
            &[("op", vec![0x02]), ("conn", (*i as u32).to_le_bytes().to_vec()), ("time", time(*ns))],
            data,
        ));
    }
    let chunk = record(
        &[("op", vec![0x05]), ("compression", b"none".to_vec()), ("size", (chunk.len() as u32).to_le_bytes().to_vec())],
        &chunk,
    );
    let start = 13 + 4096;
    let index_pos = (start + chunk.len()) as u64;
    let fields = [
        ("op", vec![0x03]),
        ("index_pos", index_pos.to_le_bytes().to_vec()),
        ("conn_count", (topics.len() as u32).to_le_bytes().to_vec()),
        ("chunk_count", 1u32.to_le_bytes().to_vec()),
    ];
    let header_len: usize = 4 + fields.iter().map(|(n, v)| 4 + n.len() + 1 + v.len()).sum::<usize>() + 4;
    let mut out = b"#ROSBAG V2.0\n".to_vec();
    out.extend(record(&fields, &vec![b' '; 4096 - header_len]));
    assert_eq!(out.len(), start);
    out.extend(chunk);
    for (i, (topic, msg_type)) in topics.iter().enumerate() {
        out.extend(connection(i as u32, topic, msg_type));
    }
    out
}

/// ROS 1 serialization, little-endian without alignment.
#[derive(Default)]
pub struct Ser(pub Vec<u8>);

impl Ser {
    pub fn u32(mut self, v: u32) -> Self {
        self.0.extend(v.to_le_bytes());
        self
    }
    pub fn str(mut self, s: &str) -> Self {
        self = self.u32(s.len() as u32);
        self.0.extend(s.as_bytes());
        self
    }
    pub fn f64s(mut self, v: &[f64]) -> Self {
        for x in v {
            self.0.extend(x.to_le_bytes());
        }
        self
    }
    /// `std_msgs/Header`: seq, stamp, frame_id.
    pub fn header(self, ns: u64, frame: &str) -> Self {
        self.u32(7).u32((ns / 1_000_000_000) as u32).u32((ns % 1_000_000_000) as u32).str(frame)
    }
}

/// `sensor_msgs/JointState`.
pub fn joint_state(ns: u64, names: &[&str], position: &[f64], velocity: &[f64]) -> Vec<u8> {
    let mut s = Ser::default().header(ns, "").u32(names.len() as u32);
    for n in names {
        s = s.str(n);
    }
    s.u32(position.len() as u32).f64s(position).u32(velocity.len() as u32).f64s(velocity).u32(0).0
}

/// `tf2_msgs/TFMessage` of `(parent, child, x, y, yaw)` transforms.
pub fn tf(ns: u64, transforms: &[(&str, &str, f64, f64, f64)]) -> Vec<u8> {
    let mut s = Ser::default().u32(transforms.len() as u32);
    for &(parent, child, x, y, yaw) in transforms {
        let q = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
        s = s.header(ns, parent).str(child).f64s(&[x, y, 0.0]).f64s(&q);
    }
    s.0
}

/// `geometry_msgs/PoseStamped` at (x, y) heading `yaw`.
pub fn pose_stamped(ns: u64, x: f64, y: f64, yaw: f64) -> Vec<u8> {
    let q = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
    Ser::default().header(ns, "world").f64s(&[x, y, 0.0]).f64s(&q).0
}
