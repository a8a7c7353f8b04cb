//! Serde for the record's `heapless::Vec` fields, as a sequence (postcard: a varint length, then
//! the items), refusing more items than the capacity.
//!
//! Here rather than heapless's own `serde` feature: the firmware shares heapless with model-core,
//! and a feature of a shared dependency would rebuild model-core differently in every image, the
//! budgeted ones included.

use core::fmt;
use core::marker::PhantomData;

use heapless::Vec;
use serde::de::{Deserialize, Deserializer, Error, SeqAccess, Visitor};
use serde::ser::{Serialize, SerializeSeq, Serializer};

/// Serialises the vector's items as a sequence.
pub(crate) fn serialize<T: Serialize, const N: usize, S: Serializer>(
    items: &Vec<T, N>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let mut seq = serializer.serialize_seq(Some(items.len()))?;
    for item in items {
        seq.serialize_element(item)?;
    }
    seq.end()
}

/// Deserialises a sequence of at most `N` items.
pub(crate) fn deserialize<'de, T: Deserialize<'de>, const N: usize, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<Vec<T, N>, D::Error> {
    struct Bounded<T, const N: usize>(PhantomData<T>);

    impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Bounded<T, N> {
        type Value = Vec<T, N>;

        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "a sequence of at most {N} items")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut items = Vec::new();
            while let Some(item) = seq.next_element()? {
                items
                    .push(item)
                    .map_err(|_| A::Error::invalid_length(N + 1, &self))?;
            }
            Ok(items)
        }
    }

    deserializer.deserialize_seq(Bounded::<T, N>(PhantomData))
}
