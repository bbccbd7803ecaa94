//! Structured mutations of TOML documents: a value replaced by a nasty one of any type, a key removed, a table emptied.
//!
//! Text mutations mostly break the syntax; these keep the document valid TOML so the
//! validation behind the parser is what gets exercised.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use toml::{Table, Value};

/// Dotted paths of every value of `t` (tables included).
fn paths(t: &Table, prefix: &[String], out: &mut Vec<Vec<String>>) {
    for (k, v) in t {
        let mut p = prefix.to_vec();
        p.push(k.clone());
        out.push(p.clone());
        if let Value::Table(inner) = v {
            paths(inner, &p, out);
        }
    }
}

fn parent_mut<'a>(t: &'a mut Table, path: &[String]) -> Option<&'a mut Table> {
    let mut cur = t;
    for k in &path[..path.len() - 1] {
        cur = cur.get_mut(k)?.as_table_mut()?;
    }
    Some(cur)
}

/// A nasty replacement for `old`: same type with an extreme value most of the time, another type sometimes.
fn nasty_value(old: &Value, rng: &mut ChaCha8Rng) -> Value {
    const FLOATS: &[f64] = &[0.0, -0.0, -1.0, 1e308, -1e308, 1e-320, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e9, 1e-9, 0.5, 100.0, 4.0, 12.0, 1e6];
    const INTS: &[i64] = &[0, -1, 1, 2, 7, 100, i64::MAX, i64::MIN, 1 << 32, 10_000, 100_000];
    let same_type = rng.random_range(0..4) != 0;
    let pick_float = |rng: &mut ChaCha8Rng| {
        let f = FLOATS[rng.random_range(0..FLOATS.len())];
        match old {
            Value::Float(x) if rng.random() => Value::Float(x * f),
            _ => Value::Float(f),
        }
    };
    match (old, same_type) {
        (Value::Float(_), true) => pick_float(rng),
        (Value::Integer(_), true) => Value::Integer(INTS[rng.random_range(0..INTS.len())]),
        (Value::String(_), true) => Value::String(super::mutate::NASTY_STRINGS[rng.random_range(0..super::mutate::NASTY_STRINGS.len())].to_string()),
        (Value::Boolean(b), true) => Value::Boolean(!b),
        (Value::Array(a), true) => {
            let mut a = a.clone();
            match rng.random_range(0..4) {
                0 => a.clear(),
                1 if !a.is_empty() => {
                    a.pop();
                }
                2 => a.push(pick_float(rng)),
                _ => {
                    if !a.is_empty() {
                        let i = rng.random_range(0..a.len());
                        a[i] = nasty_value(&a[i], rng);
                    }
                }
            }
            Value::Array(a)
        }
        (Value::Table(_), true) => Value::Table(Table::new()),
        _ => match rng.random_range(0..6) {
            0 => pick_float(rng),
            1 => Value::Integer(INTS[rng.random_range(0..INTS.len())]),
            2 => Value::String("x".into()),
            3 => Value::Boolean(true),
            4 => Value::Array(vec![]),
            _ => Value::Table(Table::new()),
        },
    }
}

/// Mutate a TOML document structurally (1 to 3 edits); `None` when `text` is not TOML.
pub fn mutate_toml(text: &str, rng: &mut ChaCha8Rng) -> Option<String> {
    let mut doc: Table = text.parse().ok()?;
    let n = rng.random_range(1..=3);
    for _ in 0..n {
        let mut all = Vec::new();
        paths(&doc, &[], &mut all);
        if all.is_empty() {
            break;
        }
        let path = all[rng.random_range(0..all.len())].clone();
        let Some(parent) = parent_mut(&mut doc, &path) else { continue };
        let key = path.last().expect("non-empty path").clone();
        match rng.random_range(0..5) {
            0 => {
                parent.remove(&key);
            }
            _ => {
                let old = parent.get(&key).cloned().unwrap_or(Value::Integer(0));
                parent.insert(key, nasty_value(&old, rng));
            }
        }
    }
    toml::to_string(&doc).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn structured_mutations_stay_toml_and_change_a_value() {
        let t = "a = 1.0\n[b]\nc = \"x\"\nd = [1, 2, 3]\n";
        let mut changed = 0;
        for s in 0..40 {
            let m = mutate_toml(t, &mut ChaCha8Rng::seed_from_u64(s)).expect("valid TOML in, TOML out");
            let back: Table = m.parse().expect("the mutation is TOML");
            changed += usize::from(back != t.parse::<Table>().unwrap());
        }
        assert!(changed >= 35, "{changed} of 40 changed the document");
        assert!(mutate_toml("= broken", &mut ChaCha8Rng::seed_from_u64(0)).is_none());
    }
}
