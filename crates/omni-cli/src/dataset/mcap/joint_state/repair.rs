//! JointState topics as real drivers publish them, mended where the data says how and refused where it
//! does not: a wheel joint named twice in a message (a stale copy beside the live one), and a wheel joint
//! missing from a message now and then.

/// A missing wheel joint is filled from its neighbours over at most this many messages in a row.
pub(super) const MAX_GAP_MESSAGES: usize = 3;
/// … and over at most this long, from the message before the gap to the one after it. s.
pub(super) const MAX_GAP_S: f64 = 0.5;

/// The other entry of a wheel joint named twice in one message.
#[derive(Clone, Copy, Debug)]
pub(super) struct Copy {
    /// The sample.
    pub k: usize,
    /// The wheel.
    pub j: usize,
    /// Its velocity and position (NaN where the field is empty).
    pub velocity: f64,
    pub position: f64,
}

/// The same value, NaN included.
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || a.is_nan() && b.is_nan()
}

/// Whether every `(velocity, position)` pair is the first one.
fn constant(values: &[(f64, f64)]) -> bool {
    values.iter().all(|&(v, p)| same(v, values[0].0) && same(p, values[0].1))
}

/// Wheel joints named twice: the speeds read (`velocity`, `position`, `samples × wheels`) hold each joint's
/// last entry, `copies` the first. Where both entries agree nothing changes; where one stays the same in
/// every message and the other changes, the one that changes is the wheel (the other is a stale copy, as a
/// driver that appends its live joints after a template leaves); where both change differently the message
/// is refused: nothing tells which is the wheel. One note per joint named twice.
pub(super) fn resolve_copies(
    copies: &[Copy],
    velocity: &mut [f64],
    position: &mut [f64],
    wheel_joints: &[String],
) -> Result<Vec<String>, (usize, String)> {
    let w = wheel_joints.len();
    let mut notes = Vec::new();
    for (j, joint) in wheel_joints.iter().enumerate() {
        let mine: Vec<&Copy> = copies.iter().filter(|c| c.j == j).collect();
        let Some(first) = mine.first() else { continue };
        let read: Vec<(f64, f64)> = mine.iter().map(|c| (velocity[c.k * w + j], position[c.k * w + j])).collect();
        let other: Vec<(f64, f64)> = mine.iter().map(|c| (c.velocity, c.position)).collect();
        let n = mine.len();
        if read.iter().zip(&other).all(|(a, b)| same(a.0, b.0) && same(a.1, b.1)) {
            notes.push(format!("joint {joint:?} is named twice in {n} messages, with the same values: read once"));
        } else if constant(&other) && !constant(&read) {
            notes.push(format!(
                "joint {joint:?} is named twice in {n} messages; its first entry never changes (velocity {}, position \
                 {}: a stale copy), so the last entry, which changes, is read",
                other[0].0, other[0].1
            ));
        } else if constant(&read) && !constant(&other) {
            for c in &mine {
                velocity[c.k * w + j] = c.velocity;
                position[c.k * w + j] = c.position;
            }
            notes.push(format!(
                "joint {joint:?} is named twice in {n} messages; its last entry never changes (velocity {}, position \
                 {}: a stale copy), so the first entry, which changes, is read",
                read[0].0, read[0].1
            ));
        } else {
            let k = mine.iter().zip(read.iter().zip(&other)).find(|(_, (a, b))| !same(a.0, b.0) || !same(a.1, b.1));
            let (c, (a, b)) = k.map_or((*first, (&read[0], &other[0])), |(c, ab)| (*c, ab));
            return Err((
                c.k,
                format!(
                    "joint {joint:?} is named twice, with different values (velocity {} and {}, position {} and {}), \
                     and neither entry stays the same from message to message: nothing tells which is the wheel; \
                     have the driver publish each joint once",
                    b.0, a.0, b.1, a.1
                ),
            ));
        }
    }
    Ok(notes)
}

/// Where wheel joints were missing: `missing` the samples `(sample, wheel)`, `first` per wheel the first
/// such message's index and problem.
pub(super) struct Gaps<'a> {
    pub missing: &'a [(usize, usize)],
    pub first: &'a [Option<(usize, String)>],
}

/// Fills each wheel joint missing from a message from the messages around it, linearly in time (held at
/// the start or end of the topic), with a note per joint counting them; a joint missing from every message,
/// or from more than [`MAX_GAP_MESSAGES`] in a row or over more than [`MAX_GAP_S`], is refused, naming the
/// gap.
pub(super) fn fill_gaps(
    gaps: &Gaps<'_>,
    t_s: &[f64],
    velocity: &mut [f64],
    position: &mut [f64],
    wheel_joints: &[String],
) -> Result<Vec<String>, (usize, String)> {
    let (n, w) = (t_s.len(), wheel_joints.len());
    let mut notes = Vec::new();
    for (j, joint) in wheel_joints.iter().enumerate() {
        let ks: Vec<usize> = gaps.missing.iter().filter(|m| m.1 == j).map(|m| m.0).collect();
        if ks.is_empty() {
            continue;
        }
        if ks.len() == n {
            let (k, what) = gaps.first.get(j).cloned().flatten().unwrap_or_default();
            return Err((k, what));
        }
        let mut longest = 0;
        for run in ks.chunk_by(|a, b| *b == a + 1) {
            let (a, b) = (run[0], run[run.len() - 1]);
            let (before, after) = (a.checked_sub(1), (b + 1 < n).then_some(b + 1));
            let span_s = t_s[after.unwrap_or(b)] - t_s[before.unwrap_or(a)];
            if run.len() > MAX_GAP_MESSAGES || span_s > MAX_GAP_S {
                return Err((
                    a,
                    format!(
                        "wheel joint {joint:?} is missing from {} messages in a row (samples {a} to {b}, {span_s:.3} s \
                         from the message before to the one after): too long a gap to fill from its neighbours (at \
                         most {MAX_GAP_MESSAGES} messages and {MAX_GAP_S} s); record the joint in every message, or \
                         cut the recording before or after the gap",
                        run.len()
                    ),
                ));
            }
            longest = longest.max(run.len());
            for values in [&mut *velocity, &mut *position] {
                for k in a..=b {
                    values[k * w + j] = match (before, after) {
                        (Some(p), Some(q)) => {
                            let f = (t_s[k] - t_s[p]) / (t_s[q] - t_s[p]);
                            values[p * w + j] + f * (values[q * w + j] - values[p * w + j])
                        }
                        (Some(p), None) => values[p * w + j],
                        (None, Some(q)) => values[q * w + j],
                        (None, None) => f64::NAN,
                    };
                }
            }
        }
        notes.push(format!(
            "wheel joint {joint:?} is missing from {} of {n} messages (at most {longest} in a row): its velocity and \
             position there are interpolated from the neighbouring messages",
            ks.len()
        ));
    }
    Ok(notes)
}
