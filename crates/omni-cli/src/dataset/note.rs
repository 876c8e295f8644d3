//! What a load noticed and the user should know ([`Note`]): the input it concerns and what happened, so a
//! load over many inputs can say a note they share once (`api::load`), by its text and not by cutting its
//! words apart.

use std::fmt;
use std::path::{Path, PathBuf};

/// One thing noticed while loading: `{source}: {text}`, or the text alone when it concerns the whole load.
#[derive(Clone, Debug, PartialEq)]
pub struct Note {
    /// The input (file, recording folder or OptiOdom set) it concerns; `None` for the load as a whole.
    pub source: Option<PathBuf>,
    /// What happened, without the input's name: the same words for every input it happened to.
    pub text: String,
}

impl Note {
    /// A note about one input.
    pub fn about(source: &Path, text: impl Into<String>) -> Self {
        Self { source: Some(source.to_path_buf()), text: text.into() }
    }

    /// A note about the load as a whole.
    pub fn general(text: impl Into<String>) -> Self {
        Self { source: None, text: text.into() }
    }
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.source {
            Some(source) => write!(f, "{}: {}", source.display(), self.text),
            None => f.write_str(&self.text),
        }
    }
}

/// As its text (JSON: `info --json`'s and Python's `notes` stay lists of strings).
impl serde::Serialize for Note {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_note_reads_as_its_input_and_text() {
        let n = Note::about(Path::new("a/b.mcap"), "topic \"/odom\": 3 messages dropped");
        assert_eq!(n.to_string(), "a/b.mcap: topic \"/odom\": 3 messages dropped");
        assert_eq!(
            serde_json::to_value(&n).unwrap(),
            serde_json::json!("a/b.mcap: topic \"/odom\": 3 messages dropped")
        );
        assert_eq!(Note::general("relative reference: 2 runs").to_string(), "relative reference: 2 runs");
    }
}
