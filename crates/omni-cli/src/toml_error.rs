//! TOML errors located the same way in every file omnical reads (robot.toml, omnical.toml, model files,
//! room files): `line L, column C: what`, on one line, the position counted in characters from 1.

/// `line L, column C: what` for an error `e` in `text` (just `what` when the parser gives no position).
pub fn locate(text: &str, e: &toml::de::Error) -> String {
    let what = e.message().trim_end();
    match e.span() {
        Some(span) => {
            let (line, column) = line_column(text, span.start);
            format!("line {line}, column {column}: {what}")
        }
        None => what.to_string(),
    }
}

/// The 1-based line and column (in characters) of byte `offset` of `text` (clamped to its end).
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_located_by_line_and_column_in_characters() {
        let text = "a = 1\n[wheel\nb = 2\n";
        let e = toml::from_str::<toml::Table>(text).unwrap_err();
        assert_eq!(locate(text, &e), "line 2, column 7: unclosed table, expected `]`");
        assert_eq!(line_column("é = \"x\nz", 7), (1, 7)); // é is two bytes, one character
        assert_eq!(line_column("é = \"x\nz", 8), (2, 1));
        assert_eq!(line_column("ab", 99), (1, 3));
    }
}
