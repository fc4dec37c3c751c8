//! Mutations of seed files: by bytes (any format) and by structure (JSON values of glTF,
//! numeric tokens of OBJ/MTL/TOML), so that a case is sometimes garbage and often a file
//! that parses but holds a hostile value (a huge count, an index past the end, NaN, -1).

use lgh_core::rng::Rng;
use serde_json::Value;

/// Numbers that break loaders: zero, signs, limits of 8/16/32-bit indices, float extremes.
const HOSTILE_NUMBERS: &[f64] = &[
    0.0,
    -0.0,
    -1.0,
    1.0,
    2.0,
    3.0,
    255.0,
    256.0,
    65535.0,
    65536.0,
    2147483647.0,
    2147483648.0,
    4294967295.0,
    4294967296.0,
    1e10,
    1e20,
    1e38,
    3.5e38,
    1e300,
    -1e300,
    1e-45,
    -2147483648.0,
    0.5,
    -0.5,
];

/// Tokens that break text formats.
const HOSTILE_TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "0",
    "-0",
    "-1",
    "4294967296",
    "99999999999",
    "",
    "//",
    "/",
    "1/2/3/4",
    "\u{0}",
    "é",
    "[",
    "]",
    "=",
    "\"",
    "#",
    "1e",
    "0x10",
    "-2147483649",
];

/// A uniform integer in `0..n` (`n > 0`).
pub fn below(rng: &mut Rng, n: usize) -> usize {
    ((u64::from(rng.next_u32()) * n.max(1) as u64) >> 32) as usize
}

fn pick<'a, T>(rng: &mut Rng, items: &'a [T]) -> &'a T {
    &items[below(rng, items.len())]
}

/// A random position in `bytes`, biased towards small lengths.
fn span(rng: &mut Rng, len: usize) -> (usize, usize) {
    if len == 0 {
        return (0, 0);
    }
    let start = below(rng, len);
    let max = (len - start).min(1 << below(rng, 10));
    (start, start + below(rng, max + 1))
}

/// One byte-level mutation of `data`: a bit flip, a hostile byte, an insertion, a deletion, a
/// duplication, a truncation, or bytes spliced in from `other`.
pub fn mutate_bytes(rng: &mut Rng, data: &mut Vec<u8>, other: &[u8]) {
    let len = data.len();
    match below(rng, 8) {
        0 if len > 0 => {
            let i = below(rng, len);
            data[i] ^= 1 << below(rng, 8);
        }
        1 if len > 0 => {
            let i = below(rng, len);
            data[i] = *pick(rng, &[0u8, 0xff, 0x7f, 0x80, b'-', b'9', b'"', b'{', b'}']);
        }
        2 => {
            let i = below(rng, len + 1);
            let n = 1 + below(rng, 16);
            let bytes: Vec<u8> = (0..n).map(|_| rng.next_u32() as u8).collect();
            data.splice(i..i, bytes);
        }
        3 => {
            let (a, b) = span(rng, len);
            data.drain(a..b);
        }
        4 => {
            let (a, b) = span(rng, len);
            let copy = data[a..b].to_vec();
            let i = below(rng, len + 1);
            data.splice(i..i, copy);
        }
        5 => data.truncate(below(rng, len + 1)),
        6 if !other.is_empty() => {
            let (a, b) = span(rng, other.len());
            let i = below(rng, len + 1);
            data.splice(i..i, other[a..b].iter().copied());
        }
        _ if len >= 4 => {
            // A little-endian u32 overwritten with a hostile count (the GLB header, chunk
            // lengths, binary buffers).
            let i = below(rng, len - 3);
            let v = *pick(rng, &[0u32, 1, 0xffff_ffff, 0x7fff_ffff, 0x1000_0000, 12]);
            data[i..i + 4].copy_from_slice(&v.to_le_bytes());
        }
        _ => data.push(rng.next_u32() as u8),
    }
}

/// Every value of a JSON tree, as paths of object keys and array indices.
fn paths(v: &Value, prefix: &mut Vec<PathStep>, out: &mut Vec<Vec<PathStep>>) {
    out.push(prefix.clone());
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                prefix.push(PathStep::Key(k.clone()));
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                prefix.push(PathStep::Index(i));
                paths(c, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone)]
enum PathStep {
    Key(String),
    Index(usize),
}

fn at<'a>(v: &'a mut Value, path: &[PathStep]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, step| match step {
        PathStep::Key(k) => v.get_mut(k.as_str()),
        PathStep::Index(i) => v.get_mut(*i),
    })
}

/// One structural mutation of a JSON document (glTF): a value replaced by a hostile number,
/// another type or a copy of another value; a key removed; an array element duplicated or
/// removed. Returns `false` if `data` is not JSON (then nothing changes).
pub fn mutate_json(rng: &mut Rng, data: &mut Vec<u8>) -> bool {
    let Ok(mut doc) = serde_json::from_slice::<Value>(data) else {
        return false;
    };
    let mut all = Vec::new();
    paths(&doc, &mut Vec::new(), &mut all);
    let path = pick(rng, &all).clone();
    let donor_path = pick(rng, &all).clone();
    let donor = at(&mut doc.clone(), &donor_path).cloned();
    let kind = below(rng, 6);
    if kind == 4 || kind == 5 {
        // Remove or duplicate in the parent container.
        if let Some((last, parent_path)) = path.split_last()
            && let Some(parent) = at(&mut doc, parent_path)
        {
            match (parent, last) {
                (Value::Object(m), PathStep::Key(k)) if kind == 4 => {
                    m.remove(k);
                }
                (Value::Array(a), PathStep::Index(i)) if kind == 4 => {
                    a.remove(*i);
                }
                (Value::Array(a), PathStep::Index(i)) => {
                    let copy = a[*i].clone();
                    a.insert(*i, copy);
                }
                _ => {}
            }
        }
    } else if let Some(target) = at(&mut doc, &path) {
        *target = match kind {
            0 | 1 => serde_json::Number::from_f64(*pick(rng, HOSTILE_NUMBERS))
                .map_or(Value::Null, Value::Number),
            2 => pick(
                rng,
                &[
                    Value::Null,
                    Value::Bool(true),
                    Value::String("x".into()),
                    Value::Array(vec![]),
                    Value::Object(serde_json::Map::new()),
                ],
            )
            .clone(),
            _ => donor.unwrap_or(Value::Null),
        };
    }
    *data = serde_json::to_vec(&doc).unwrap_or_default();
    true
}

/// One token-level mutation of a text format (OBJ, MTL, TOML): a whitespace-separated token
/// (a number, an index, a key) replaced by a hostile token or number, or a line duplicated or
/// removed.
pub fn mutate_text(rng: &mut Rng, data: &mut Vec<u8>) {
    let text = String::from_utf8_lossy(data).into_owned();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        lines.push(String::new());
    }
    let li = below(rng, lines.len());
    match below(rng, 5) {
        0 => {
            let copy = lines[li].clone();
            lines.insert(li, copy);
        }
        1 => {
            lines.remove(li);
        }
        _ => {
            let mut tokens: Vec<String> =
                lines[li].split(' ').map(str::to_string).collect::<Vec<_>>();
            let ti = below(rng, tokens.len());
            tokens[ti] = if below(rng, 2) == 0 {
                (*pick(rng, HOSTILE_TOKENS)).to_string()
            } else {
                format!("{}", pick(rng, HOSTILE_NUMBERS))
            };
            lines[li] = tokens.join(" ");
        }
    }
    *data = (lines.join("\n") + "\n").into_bytes();
}
