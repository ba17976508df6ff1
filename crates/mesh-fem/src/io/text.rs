//! Allocation-free helpers for line-oriented ASCII formats.

/// Iterates over the lines of a byte buffer as `(1-based line number, line)`, with `\n`,
/// `\r\n` and lone `\r` endings removed.
pub(crate) struct Lines<'a> {
    rest: &'a [u8],
    line: usize,
}

impl<'a> Lines<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { rest: bytes, line: 0 }
    }

    /// Number of the line returned last (0 before the first).
    pub fn line(&self) -> usize {
        self.line
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() {
            return None;
        }
        self.line += 1;
        let end = self
            .rest
            .iter()
            .position(|&b| b == b'\n' || b == b'\r')
            .unwrap_or(self.rest.len());
        let line = &self.rest[..end];
        let mut next = end;
        if next < self.rest.len() {
            // `\r\n` counts as one line break.
            if self.rest[next] == b'\r' && self.rest.get(next + 1) == Some(&b'\n') {
                next += 1;
            }
            next += 1;
        }
        self.rest = &self.rest[next..];
        Some((self.line, line))
    }
}

/// Whitespace-separated tokens of one line.
pub(crate) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty())
}

/// The line up to (not including) a `#` comment.
pub(crate) fn strip_comment(line: &[u8]) -> &[u8] {
    match line.iter().position(|&b| b == b'#') {
        Some(i) => &line[..i],
        None => line,
    }
}

/// Parses a float token (`1`, `-2.5e-3`, `nan`, `inf`; Rust's grammar, which covers the
/// C/Python output found in mesh files).
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// Parses a signed integer token.
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A short, printable excerpt of a token for error messages.
pub(crate) fn show(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(token);
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_handle_lf_crlf_and_cr() {
        let v: Vec<_> = Lines::new(b"a\r\nb\nc\rd").collect();
        assert_eq!(v, vec![(1, &b"a"[..]), (2, &b"b"[..]), (3, &b"c"[..]), (4, &b"d"[..])]);
        let v: Vec<_> = Lines::new(b"a\n\nb\n").collect();
        assert_eq!(v, vec![(1, &b"a"[..]), (2, &b""[..]), (3, &b"b"[..])]);
    }
}
