//! The bridge's payloads: CBOR (RFC 8949) maps, documented in README § Live coupling.
//!
//! Why CBOR: self-describing like JSON (a Python or C peer decodes it without a schema, e.g.
//! `cbor2.loads`), but binary, so an f64 travels exactly and in at most 9 bytes, and particle
//! arrays travel as byte strings of little-endian f64 (numpy: `np.frombuffer(b, "<f8")`).
//!
//! - output sample `<prefix>/out/<name>`: `{"t": time, "v": number | [numbers]}`
//! - input `<prefix>/in/<name>`: a number, an array of numbers, or `{"v": ...}` (so an output
//!   sample can be forwarded as it is); a 3-vector may be given with the case's dimension only.

use ciborium::Value;

pub fn encode(v: &Value) -> Vec<u8> {
    let mut out = Vec::new();
    ciborium::into_writer(v, &mut out).expect("writing CBOR to a Vec cannot fail");
    out
}

pub fn decode(bytes: &[u8]) -> Result<Value, String> {
    ciborium::from_reader::<Value, _>(bytes).map_err(|e| format!("not CBOR ({e})"))
}

/// A CBOR map with text keys.
pub fn map(pairs: Vec<(&str, Value)>) -> Value {
    Value::Map(
        pairs
            .into_iter()
            .map(|(k, v)| (Value::Text(k.into()), v))
            .collect(),
    )
}

/// Entry `key` of a CBOR map.
pub fn field<'a>(v: &'a Value, key: &str) -> Option<&'a Value> {
    match v {
        Value::Map(m) => m
            .iter()
            .find(|(k, _)| matches!(k, Value::Text(t) if t == key))
            .map(|(_, v)| v),
        _ => None,
    }
}

/// A number or an array of numbers (integers allowed).
pub fn numbers(v: &[f64]) -> Value {
    if v.len() == 1 {
        Value::Float(v[0])
    } else {
        Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
    }
}

/// One output sample: `{"t": time, "v": value}`.
pub fn sample(t: f64, value: Value) -> Vec<u8> {
    encode(&map(vec![("t", Value::Float(t)), ("v", value)]))
}

/// Little-endian f64 bytes.
pub fn f64_bytes(xs: impl Iterator<Item = f64>) -> Value {
    Value::Bytes(xs.flat_map(|x| x.to_le_bytes()).collect())
}

pub fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Integer(i) => Some(i128::from(*i) as f64),
        _ => None,
    }
}

/// The values of input `name` (of `size` elements, 1 or a 3-vector in a `dimension`-D case)
/// from a payload; finite numbers only. The reason when not.
pub fn input_values(
    bytes: &[u8],
    name: &str,
    size: usize,
    dimension: usize,
) -> Result<Vec<f64>, String> {
    let v = decode(bytes).map_err(|e| format!("{name}: payload {e}"))?;
    values_of(&v, name, size, dimension)
}

/// `input_values` of a decoded value.
pub fn values_of(v: &Value, name: &str, size: usize, dimension: usize) -> Result<Vec<f64>, String> {
    let v = field(v, "v").unwrap_or(v);
    let xs: Vec<f64> = match v {
        Value::Array(a) => a
            .iter()
            .map(number)
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| format!("{name}: the array must hold numbers only"))?,
        other => vec![number(other).ok_or_else(|| {
            format!("{name}: expected a number, an array of numbers or {{\"v\": ...}}")
        })?],
    };
    let mut xs = xs;
    if size == 3 && xs.len() == dimension && dimension < 3 {
        xs.resize(3, 0.0);
    }
    if xs.len() != size {
        return Err(format!(
            "{name}: expected {} got {} values",
            if size == 1 {
                "1 value,".to_string()
            } else {
                format!("{size} (or {dimension}) values,")
            },
            xs.len()
        ));
    }
    if let Some(x) = xs.iter().find(|x| !x.is_finite()) {
        return Err(format!("{name}: values must be finite, got {x}"));
    }
    Ok(xs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_decode_in_every_documented_form_and_bad_ones_say_why() {
        let g = encode(&numbers(&[0.5, -9.81]));
        assert_eq!(
            input_values(&g, "gravity", 3, 2).unwrap(),
            [0.5, -9.81, 0.0]
        );
        let s = sample(1.25, numbers(&[2e4]));
        assert_eq!(input_values(&s, "p", 1, 2).unwrap(), [2e4]);
        let i = encode(&Value::Integer(3.into()));
        assert_eq!(input_values(&i, "p", 1, 2).unwrap(), [3.0]);
        for (bytes, needle) in [
            (b"\xff\x00".to_vec(), "not CBOR"),
            (encode(&Value::Text("x".into())), "expected a number"),
            (encode(&numbers(&[1.0, 2.0])), "expected 1 value"),
            (encode(&numbers(&[1.0, 2.0, 3.0, 4.0])), "expected 3 (or 2)"),
            (encode(&numbers(&[f64::NAN])), "finite"),
            (
                encode(&Value::Array(vec![Value::Text("a".into())])),
                "numbers only",
            ),
        ] {
            let size = if needle.starts_with("expected 3") {
                3
            } else {
                1
            };
            let e = input_values(&bytes, "x", size, 2).unwrap_err();
            assert!(e.starts_with("x: ") && e.contains(needle), "{e}");
        }
        // exact round trip of an f64 through a sample
        let t = 0.1 + 0.2;
        let v = decode(&sample(t, numbers(&[t]))).unwrap();
        assert_eq!(number(field(&v, "t").unwrap()), Some(t));
    }
}
