//! How a message shows text it did not write: a path ([`show`]), a value the user gave ([`quote`]),
//! another crate's message ([`shorten_words`]): control characters escaped, long values cut, so
//! that every message stays one readable line.
//!
//! Imports nothing of this crate: [`crate::error`] displays paths through it, and [`crate::fsio`]
//! (which returns those errors) re-exports it, so the imports run one way.

use std::path::Path;

/// The most characters of a bad value a message quotes: enough to recognise it, short enough that a
/// 100 MB field still gives one short line.
pub const QUOTE_CHARS: usize = 80;

/// `s` for a message: control characters (and other non-printing ones) escaped as `\n`, `\u{1b}`…,
/// cut to [`QUOTE_CHARS`] characters with `…` and the full length in bytes when longer.
pub fn quote(s: &str) -> String {
    let mut out = String::new();
    for (shown, c) in s.chars().enumerate() {
        if shown == QUOTE_CHARS {
            out.push_str(&format!("… ({} bytes in all)", s.len()));
            return out;
        }
        escape_char(c, &mut out);
    }
    out
}

/// `msg` with control characters escaped and every word (run without a space) longer than `max`
/// characters cut to `max`, with its length in bytes: for messages of other crates that echo a value
/// whole (serde's `unknown field `…``, `invalid type: string "…"`).
pub fn shorten_words(msg: &str, max: usize) -> String {
    let escaped = escape_controls(msg);
    let mut out = String::with_capacity(escaped.len().min(4096));
    for (k, word) in escaped.split(' ').enumerate() {
        if k > 0 {
            out.push(' ');
        }
        if word.chars().count() > max {
            out.extend(word.chars().take(max));
            out.push_str(&format!("…({} bytes)", word.len()));
        } else {
            out.push_str(word);
        }
    }
    out
}

/// Escapes control characters of a whole message (which stays as long as it is).
pub fn escape_controls(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        escape_char(c, &mut out);
    }
    out
}

fn escape_char(c: char, out: &mut String) {
    if c.is_control() || matches!(c, '\u{200b}'..='\u{200f}' | '\u{2028}'..='\u{202e}' | '\u{feff}') {
        out.extend(c.escape_default());
    } else {
        out.push(c);
    }
}

/// A path for a message: [`escape_controls`] of its display form.
pub fn show(path: &Path) -> String {
    escape_controls(&path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quote_cuts_and_escapes() {
        assert_eq!(quote("a\nb\u{1b}"), "a\\nb\\u{1b}");
        let long = "x".repeat(1000);
        let q = quote(&long);
        assert!(q.starts_with(&"x".repeat(QUOTE_CHARS)) && q.ends_with("(1000 bytes in all)"), "{q}");
    }

    #[test]
    fn show_escapes_a_path() {
        assert_eq!(show(Path::new("a\nb.png")), "a\\nb.png");
    }
}
