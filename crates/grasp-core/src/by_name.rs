//! Unit enums read by name from problem files.
//!
//! serde's derived enums reject a value of the wrong JSON type (a number, `null`, an
//! array) with serde_json's bare "expected value". Reading them as strings instead
//! gives "invalid type: integer `1`, expected one of `fpc`, `pcwf`, `sfcl`, `sfce`",
//! and keeps serde's "unknown variant" message for a misspelt name.

use serde::de::{Deserializer, Error, Visitor};
use std::fmt;
use std::marker::PhantomData;

/// An enum without data whose variants are named in files, as its `Serialize` writes
/// them (grasp-io's `enum_names_round_trip` test checks every one).
pub trait ByName: Copy + 'static {
    /// Every variant, in the order of [`Self::NAMES`].
    const VARIANTS: &'static [Self];
    /// Each variant's name in files.
    const NAMES: &'static [&'static str];
}

/// Reads a [`ByName`] enum from its name; the `Deserialize` impls of such enums call it.
pub fn deserialize<'de, D: Deserializer<'de>, T: ByName>(d: D) -> Result<T, D::Error> {
    d.deserialize_str(NameVisitor(PhantomData))
}

struct NameVisitor<T>(PhantomData<T>);

impl<T: ByName> Visitor<'_> for NameVisitor<T> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("one of ")?;
        for (i, name) in T::NAMES.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}`{name}`")?;
        }
        Ok(())
    }

    fn visit_str<E: Error>(self, v: &str) -> Result<T, E> {
        match T::NAMES.iter().position(|n| *n == v) {
            Some(i) => Ok(T::VARIANTS[i]),
            None => Err(E::unknown_variant(v, T::NAMES)),
        }
    }
}

/// Implements `Deserialize` by name for an enum that implements [`ByName`] (in a crate
/// that depends on serde).
#[macro_export]
macro_rules! deserialize_by_name {
    ($t:ty) => {
        impl<'de> serde::Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $crate::by_name::deserialize(d)
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use crate::{InternalForces, SfceSpacing};

    fn read<T: serde::de::DeserializeOwned>(json: &str) -> Result<T, String> {
        serde_json::from_str(json).map_err(|e| e.to_string())
    }

    #[test]
    fn names_and_wrong_types_are_explained() {
        assert_eq!(read::<InternalForces>("\"free\""), Ok(InternalForces::Free));
        assert_eq!(read::<SfceSpacing>("\"paper\""), Ok(SfceSpacing::Paper));
        let expected = "expected one of `compliance`, `euclidean`, `free`";
        for (json, got) in [
            ("1", "invalid type: integer `1`"),
            ("null", "invalid type: null"),
            ("[]", "invalid type: sequence"),
            ("{}", "invalid type: map"),
            ("\"Free\"", "unknown variant `Free`"),
        ] {
            let e = read::<InternalForces>(json).unwrap_err();
            assert!(e.starts_with(&format!("{got}, {expected}")), "{json}: {e}");
        }
    }
}
