//! Text quoted for messages as `{:?}` quotes it, without std's Unicode
//! tables. `Debug` for `str` and `char` decides which characters to escape
//! from tables of printable and grapheme-extending characters (8.6 KB of
//! data and 1.8 KB of code in the core wasm module); the messages quote
//! config strings and format names from logs, mostly ASCII. So: the same
//! output as `{:?}` for every character below U+0100 (a test holds the two
//! together), and every character above it as a `\u{...}` escape, where
//! `{:?}` would show the printable ones as they are. Unambiguous either
//! way, and a corrupt log's bytes read back the same.

/// `s` in double quotes, as `format!("{s:?}")` gives it below U+0100.
pub fn quoted(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        escape(c, '"', &mut out);
    }
    out.push('"');
    out
}

/// `c` in single quotes, as `format!("{c:?}")` gives it below U+0100.
pub fn quoted_char(c: char) -> String {
    let mut out = String::with_capacity(8);
    out.push('\'');
    escape(c, '\'', &mut out);
    out.push('\'');
    out
}

/// Push `c` as it appears between `quote`s.
fn escape(c: char, quote: char, out: &mut String) {
    let shown = match c {
        '\0' => Some('0'),
        '\t' => Some('t'),
        '\r' => Some('r'),
        '\n' => Some('n'),
        '\\' => Some('\\'),
        _ if c == quote => Some(c),
        _ => None,
    };
    if let Some(e) = shown {
        out.push('\\');
        out.push(e);
    } else if matches!(c, ' '..='~') || (c > '\u{a0}' && c <= '\u{ff}' && c != '\u{ad}') {
        // Printable ASCII, and Latin-1's printable half (U+00A0, the
        // no-break space, and U+00AD, the soft hyphen, are escaped).
        out.push(c);
    } else {
        hex(c as u32, out);
    }
}

/// `\u{...}` with the fewest lowercase hex digits, as std writes it.
fn hex(mut n: u32, out: &mut String) {
    let mut digits = [0u8; 8];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b"0123456789abcdef"[(n & 15) as usize];
        n >>= 4;
        if n == 0 {
            break;
        }
    }
    out.push_str("\\u{");
    for &d in &digits[k..] {
        out.push(d as char);
    }
    out.push('}');
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every character below U+0100, alone and inside text, as std quotes
    /// it; above U+00FF, escapes.
    #[test]
    fn as_debug_below_u0100() {
        let mut checked = 0;
        for c in (0u32..0x100).filter_map(char::from_u32) {
            assert_eq!(quoted_char(c), format!("{c:?}"), "U+{:04X}", c as u32);
            let s = format!("a{c}\"'b");
            assert_eq!(quoted(&s), format!("{s:?}"), "U+{:04X}", c as u32);
            checked += 1;
        }
        assert_eq!(checked, 256);
        assert_eq!(quoted("x\u{200b}中\u{fffd}😀"), "\"x\\u{200b}\\u{4e2d}\\u{fffd}\\u{1f600}\"");
        assert_eq!(quoted_char('\u{10ffff}'), "'\\u{10ffff}'");
        assert_eq!(quoted(""), "\"\"");
    }
}
