//! Mutations of valid inputs: byte flips, token and number substitutions, line deletions and duplications, truncation, splices.
//!
//! Every mutation takes the case's seeded random generator, so a case is reproducible from
//! (format, seed, case index) alone.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Values that break parsers and validators: zero, negatives, overflow, underflow,
/// NaN / infinities in the spellings TOML and Rust accept, integer limits, empty.
pub const NASTY_NUMBERS: &[&str] = &[
    "0", "-0", "0.0", "-1", "1", "2", "-1e308", "1e308", "1.8e308", "1e-320", "4.9e-324", "nan", "NaN", "-nan", "inf", "-inf",
    "infinity", "9223372036854775807", "-9223372036854775808", "18446744073709551616", "4294967297", "99999999999999999999999",
    "1e9", "1e15", "-7", "0.5", "", "\"\"", "\"x\"", "true", "[]", "{}", "[1.0, 2.0]", "1e3", "65536", "3",
];

/// Strings that break name and enum handling.
pub const NASTY_STRINGS: &[&str] = &["", "x", "none", "..", "/", "a/b", "\u{0}", "é", "sphere", "discocyte", "periodic-channel", "-", "'"];

/// Replace one number-like token (`[-+]?digit...`, `nan`, `inf`) of `text` by a nasty value.
pub fn substitute_number(text: &str, rng: &mut ChaCha8Rng) -> String {
    let spans = number_spans(text);
    if spans.is_empty() {
        return insert_line(text, rng);
    }
    let (a, b) = spans[rng.random_range(0..spans.len())];
    let with = NASTY_NUMBERS[rng.random_range(0..NASTY_NUMBERS.len())];
    format!("{}{}{}", &text[..a], with, &text[b..])
}

/// Byte spans of number-like tokens in `text`.
pub fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start_ok = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        let signed = (b[i] == b'-' || b[i] == b'+') && i + 1 < b.len() && b[i + 1].is_ascii_digit();
        if start_ok && (b[i].is_ascii_digit() || signed) {
            let mut j = i + 1;
            while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'_') || ((b[j] == b'-' || b[j] == b'+') && matches!(b[j - 1], b'e' | b'E'))) {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Replace the contents of one double-quoted string of `text` by a nasty string.
pub fn substitute_string(text: &str, rng: &mut ChaCha8Rng) -> String {
    let quotes: Vec<usize> = text.match_indices('"').map(|(i, _)| i).collect();
    if quotes.len() < 2 {
        return substitute_number(text, rng);
    }
    let k = rng.random_range(0..quotes.len() / 2) * 2;
    let (a, b) = (quotes[k] + 1, quotes[k + 1]);
    let with = NASTY_STRINGS[rng.random_range(0..NASTY_STRINGS.len())];
    format!("{}{}{}", &text[..a], with, &text[b..])
}

fn lines(text: &str) -> Vec<&str> {
    text.split_inclusive('\n').collect()
}

/// Delete one line.
pub fn delete_line(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut l = lines(text);
    if !l.is_empty() {
        l.remove(rng.random_range(0..l.len()));
    }
    l.concat()
}

/// Duplicate one line (in place or at another position).
pub fn duplicate_line(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut l = lines(text);
    if l.is_empty() {
        return text.to_string();
    }
    let line = l[rng.random_range(0..l.len())];
    let line = if line.ends_with('\n') { line.to_string() } else { format!("{line}\n") };
    let at = rng.random_range(0..=l.len());
    let mut out: Vec<String> = l.drain(..).map(str::to_string).collect();
    out.insert(at, line);
    out.concat()
}

/// Swap two lines.
pub fn swap_lines(text: &str, rng: &mut ChaCha8Rng) -> String {
    let mut l: Vec<String> = lines(text).into_iter().map(|s| if s.ends_with('\n') { s.to_string() } else { format!("{s}\n") }).collect();
    if l.len() >= 2 {
        let (a, b) = (rng.random_range(0..l.len()), rng.random_range(0..l.len()));
        l.swap(a, b);
    }
    l.concat()
}

/// Insert a short junk line.
pub fn insert_line(text: &str, rng: &mut ChaCha8Rng) -> String {
    const JUNK: &[&str] = &["[x]\n", "a = 1\n", ",,,\n", "\"\n", "=\n", "[[cell]]\n", "1,2,3,4,5,6,7,8,9,10,11,12,13,14\n", "\n", "#\n", "key = \"\n"];
    let mut l: Vec<String> = lines(text).into_iter().map(str::to_string).collect();
    let at = rng.random_range(0..=l.len());
    l.insert(at, JUNK[rng.random_range(0..JUNK.len())].to_string());
    l.concat()
}

/// Any of the text mutations (1 to 3 of them), keeping the result valid UTF-8 unless a byte mutation was drawn.
pub fn mutate_text(text: &str, rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut t = text.to_string();
    let n = rng.random_range(1..=3);
    for _ in 0..n {
        t = match rng.random_range(0..10) {
            0..=3 => substitute_number(&t, rng),
            4 => substitute_string(&t, rng),
            5 => delete_line(&t, rng),
            6 => duplicate_line(&t, rng),
            7 => swap_lines(&t, rng),
            8 => insert_line(&t, rng),
            _ => return mutate_bytes(t.as_bytes(), rng, 2),
        };
    }
    if rng.random_range(0..20) == 0 {
        let cut = rng.random_range(0..=t.len());
        return t.as_bytes()[..cut].to_vec();
    }
    t.into_bytes()
}

/// Interesting integers written over 1, 2, 4 or 8 bytes (little and big endian).
const NASTY_INTS: &[u64] = &[0, 1, 2, 0x7f, 0x80, 0xff, 0x7fff, 0xffff, 0x7fff_ffff, 0xffff_ffff, u64::MAX, 1 << 40, 0x100];

/// 1 to `max_ops` byte mutations of `data`: bit flips, nasty integers, deletions, duplications, truncation.
pub fn mutate_bytes(data: &[u8], rng: &mut ChaCha8Rng, max_ops: usize) -> Vec<u8> {
    let mut d = data.to_vec();
    let n = rng.random_range(1..=max_ops.max(1));
    for _ in 0..n {
        let pos = if d.is_empty() { 0 } else { rng.random_range(0..d.len()) };
        mutate_at(&mut d, pos, rng);
    }
    d
}

/// One byte mutation at `pos` (clamped to the data).
pub fn mutate_at(d: &mut Vec<u8>, pos: usize, rng: &mut ChaCha8Rng) {
    if d.is_empty() {
        d.push(rng.random());
        return;
    }
    let pos = pos.min(d.len() - 1);
    match rng.random_range(0..8) {
        0 | 1 => d[pos] ^= 1 << rng.random_range(0..8),
        2 => d[pos] = rng.random(),
        3 => {
            let v = NASTY_INTS[rng.random_range(0..NASTY_INTS.len())];
            let width = [1usize, 2, 4, 8][rng.random_range(0..4)];
            let bytes = if rng.random() { v.to_le_bytes() } else { v.to_be_bytes() };
            let src = if bytes[0] == 0 && width < 8 { &bytes[8 - width..] } else { &bytes[..width] };
            for (k, b) in src.iter().enumerate() {
                if pos + k < d.len() {
                    d[pos + k] = *b;
                }
            }
        }
        4 => {
            let len = rng.random_range(1..=16).min(d.len() - pos);
            d.drain(pos..pos + len);
        }
        5 => {
            let len = rng.random_range(1..=64).min(d.len() - pos);
            let chunk = d[pos..pos + len].to_vec();
            let at = rng.random_range(0..=d.len());
            d.splice(at..at, chunk);
        }
        6 => d.truncate(pos),
        _ => {
            let len = rng.random_range(1..=8);
            let junk: Vec<u8> = (0..len).map(|_| rng.random()).collect();
            d.splice(pos..pos, junk);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn number_spans_find_numbers_and_not_names() {
        let t = "level = 3\nradius_um = -4.5e-1\nname = \"r2d2\"\nx = [1.0, 2]\n";
        let spans: Vec<&str> = number_spans(t).into_iter().map(|(a, b)| &t[a..b]).collect();
        assert_eq!(spans, ["3", "-4.5e-1", "1.0", "2"]);
    }

    #[test]
    fn mutations_are_deterministic_and_change_the_text() {
        let t = "a = 1.0\nb = \"x\"\nc = 3\n";
        let run = |seed| mutate_text(t, &mut ChaCha8Rng::seed_from_u64(seed));
        assert_eq!(run(7), run(7));
        let changed = (0..50).filter(|s| run(*s) != t.as_bytes()).count();
        assert!(changed >= 45, "only {changed} of 50 mutations changed the text");
    }
}
