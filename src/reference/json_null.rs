//! Floats that JSON cannot hold, written as null: serde helpers (`#[serde(with = ...)]`) for the
//! cached references' files.

/// Serialises NaN ("not computed") as JSON null, which plain `f64` cannot read back.
pub mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    type Values = Vec<Vec<[f64; 3]>>;

    pub fn serialize<S: Serializer>(v: &Values, s: S) -> Result<S::Ok, S::Error> {
        let opt: Vec<Vec<[Option<f64>; 3]>> =
            v.iter().map(|o| o.iter().map(|m| m.map(|x| (!x.is_nan()).then_some(x))).collect()).collect();
        opt.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Values, D::Error> {
        let opt = Vec::<Vec<[Option<f64>; 3]>>::deserialize(d)?;
        Ok(opt.into_iter().map(|o| o.into_iter().map(|m| m.map(|x| x.unwrap_or(f64::NAN))).collect()).collect())
    }
}

/// Serialises an infinite `f64` as JSON null (which plain `f64` cannot read back) and reads
/// null back as infinity.
pub mod infinite_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        v.is_finite().then_some(*v).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}
