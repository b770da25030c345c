//! How `summary.json` writes a figure that is not a finite number: as the
//! string `"NaN"`, `"inf"` or `"-inf"` (JSON has no such numbers, and
//! serde_json would silently write `null`). Every such figure sits beside a
//! field that says why (a verdict, a failed-tick count).

use serde::{Deserialize, Deserializer, Serializer};

/// Serialises a finite `v` as a number, anything else as its name.
pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_f64(*v)
    } else if v.is_nan() {
        s.serialize_str("NaN")
    } else if *v > 0.0 {
        s.serialize_str("inf")
    } else {
        s.serialize_str("-inf")
    }
}

/// Reads what [`serialize`] wrote.
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Figure {
        Number(f64),
        Text(String),
    }
    match Figure::deserialize(d)? {
        Figure::Number(v) => Ok(v),
        Figure::Text(t) => match t.as_str() {
            "NaN" => Ok(f64::NAN),
            "inf" => Ok(f64::INFINITY),
            "-inf" => Ok(f64::NEG_INFINITY),
            other => Err(serde::de::Error::custom(format!(
                "expected a number, \"NaN\", \"inf\" or \"-inf\", got {other:?}"
            ))),
        },
    }
}

#[cfg(test)]
mod tests {
    #[derive(serde::Serialize, serde::Deserialize)]
    struct F(#[serde(with = "super")] f64);

    #[test]
    fn non_finite_figures_are_written_by_name_and_read_back() {
        for (v, text) in [
            (1.5, "1.5"),
            (f64::NAN, "\"NaN\""),
            (f64::INFINITY, "\"inf\""),
            (f64::NEG_INFINITY, "\"-inf\""),
        ] {
            let json = serde_json::to_string(&F(v)).unwrap();
            assert_eq!(json, text);
            let back: F = serde_json::from_str(&json).unwrap();
            assert!(back.0 == v || (v.is_nan() && back.0.is_nan()));
        }
    }
}
