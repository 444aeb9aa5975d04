//! Keyframes (docs/model.md §6.1): a value of the scene given either
//! plainly or as keys at frame numbers, `{"keys": [{"frame": F, "value":
//! V}, ...]}`, and its value at any frame: held before the first key and
//! after the last, exactly a key's value at its frame, and between two keys
//! interpolated linearly (angles in degrees too, which is the spherical
//! interpolation of a rotation about a fixed axis). Only the serde form and
//! the arithmetic live here; which values may be keyed is the format's
//! business (`format`), the scene at a frame `animate`'s.

use std::marker::PhantomData;

use schemars::JsonSchema;
use serde::de::{DeserializeOwned, DeserializeSeed, Error as _, IntoDeserializer, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// The largest frame number: frames are `u32` on the command line and in
/// file names.
pub const MAX_FRAME: f64 = u32::MAX as f64;

/// A value that keys can interpolate.
pub trait Keyable: Clone + DeserializeOwned {
    /// What a plain value looks like, for error messages.
    const EXPECTING: &'static str;

    /// The value a fraction `t` (`0 < t < 1`) of the way from `a` to `b`.
    fn lerp(a: &Self, b: &Self, t: f64) -> Self;
}

/// `(1 − t)·a + t·b`: exactly `a` at `t = 0` and `b` at `t = 1`, and
/// exact for the round values keys usually hold (`0 → 90` at `t = 0.5` is
/// 45).
pub fn lerp(a: f64, b: f64, t: f64) -> f64 {
    (1.0 - t) * a + t * b
}

impl Keyable for f64 {
    const EXPECTING: &'static str = "a number";

    fn lerp(a: &f64, b: &f64, t: f64) -> f64 {
        lerp(*a, *b, t)
    }
}

impl Keyable for [f64; 3] {
    const EXPECTING: &'static str = "an array [x, y, z]";

    fn lerp(a: &Self, b: &Self, t: f64) -> Self {
        [lerp(a[0], b[0], t), lerp(a[1], b[1], t), lerp(a[2], b[2], t)]
    }
}

/// One key: the value at a frame.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Key<T> {
    /// The frame number, 0 to 4294967295 (fractions allowed).
    #[schemars(range(min = 0, max = 4294967295.0))]
    pub frame: f64,
    /// The value at that frame.
    pub value: T,
}

/// Keys: at least one, their frames strictly increasing, each within
/// `0..=MAX_FRAME` (checked as they are read).
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(description = "Keys: at least one, their frames strictly increasing.")]
pub struct Keys<T> {
    /// The keys in order of their frames.
    #[schemars(length(min = 1))]
    keys: Vec<Key<T>>,
}

/// Where a frame falls among the keys.
#[derive(Debug, PartialEq)]
pub enum Segment<'a, T> {
    /// On a key, before the first or after the last: that key's value.
    Held(&'a T),
    /// Strictly between keys `index − 1` and `index`, a fraction `t` of the way.
    Between {
        /// The key before the frame.
        from: &'a T,
        /// The key after it.
        to: &'a T,
        /// `0 < t < 1`.
        t: f64,
        /// The later key's index, to name it in errors.
        index: usize,
    },
}

impl<T> Keys<T> {
    /// The keys in frame order (never empty).
    pub fn keys(&self) -> &[Key<T>] {
        &self.keys
    }

    /// The first key's value: the value at every frame up to the first key.
    pub fn first(&self) -> &T {
        // Never empty: the reader refuses an empty list.
        &self.keys[0].value
    }

    /// Where `frame` falls: on or outside the keys (held), or between two.
    pub fn segment(&self, frame: f64) -> Segment<'_, T> {
        // The first key after `frame`; the keys are few, but the search is
        // as cheap as a scan and does not grow with them.
        let after = self.keys.partition_point(|k| k.frame <= frame);
        if after == 0 {
            return Segment::Held(self.first());
        }
        let before = &self.keys[after - 1];
        match self.keys.get(after) {
            Some(next) if before.frame != frame => {
                // Frames lie in 0..=MAX_FRAME: no overflow, and 0 < t < 1.
                let t = (frame - before.frame) / (next.frame - before.frame);
                Segment::Between { from: &before.value, to: &next.value, t, index: after }
            }
            _ => Segment::Held(&before.value),
        }
    }
}

impl<T: Keyable> Keys<T> {
    /// The value at `frame`, interpolated linearly.
    pub fn at(&self, frame: f64) -> T {
        match self.segment(frame) {
            Segment::Held(v) => v.clone(),
            Segment::Between { from, to, t, .. } => T::lerp(from, to, t),
        }
    }

    /// Reads the list of keys, checking each as it comes.
    fn read_list<'de, A: SeqAccess<'de>>(mut seq: A) -> Result<Self, A::Error> {
        let mut keys: Vec<Key<T>> = Vec::with_capacity(seq.size_hint().unwrap_or(2).min(64));
        while let Some(key) = seq.next_element_seed(NextKey::<T>(keys.last().map(|k| k.frame), PhantomData))? {
            keys.push(key);
        }
        if keys.is_empty() {
            return Err(A::Error::custom("keys must not be empty: give at least one {\"frame\": F, \"value\": V}"));
        }
        Ok(Keys { keys })
    }
}

/// Reads one key and checks its frame against the one before, so that an
/// error names the key (`keys[2]`).
struct NextKey<T>(Option<f64>, PhantomData<T>);

impl<'de, T: Keyable> DeserializeSeed<'de> for NextKey<T> {
    type Value = Key<T>;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Key<T>, D::Error> {
        let key = Key::<T>::deserialize(deserializer)?;
        if !(0.0..=MAX_FRAME).contains(&key.frame) {
            let msg = format!("a key's frame must be between 0 and 4294967295, got {}", key.frame);
            return Err(D::Error::custom(msg));
        }
        if let Some(previous) = self.0 {
            if key.frame <= previous {
                let msg = format!("key frames must increase: frame {} follows frame {previous}", key.frame);
                return Err(D::Error::custom(msg));
            }
        }
        Ok(key)
    }
}

impl<'de, T: Keyable> Deserialize<'de> for Keys<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Object<T>(PhantomData<T>);
        impl<'de, T: Keyable> Visitor<'de> for Object<T> {
            type Value = Keys<T>;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("{\"keys\": [{\"frame\": F, \"value\": V}, ...]}")
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Keys<T>, A::Error> {
                keys_from_map(map)
            }
        }
        deserializer.deserialize_map(Object(PhantomData))
    }
}

/// The rest of an object whose keys are being read: exactly one member,
/// `keys`.
fn keys_from_map<'de, T: Keyable, A: MapAccess<'de>>(mut map: A) -> Result<Keys<T>, A::Error> {
    let mut keys = None;
    while let Some(name) = map.next_key::<String>()? {
        if name != "keys" {
            return Err(A::Error::unknown_field(&name, &["keys"]));
        }
        if keys.is_some() {
            return Err(A::Error::duplicate_field("keys"));
        }
        keys = Some(map.next_value_seed(KeyList(PhantomData))?);
    }
    keys.ok_or_else(|| A::Error::missing_field("keys"))
}

/// Reads the list under `keys`.
struct KeyList<T>(PhantomData<T>);

impl<'de, T: Keyable> DeserializeSeed<'de> for KeyList<T> {
    type Value = Keys<T>;

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Keys<T>, D::Error> {
        struct List<T>(PhantomData<T>);
        impl<'de, T: Keyable> Visitor<'de> for List<T> {
            type Value = Keys<T>;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a list of keys [{\"frame\": F, \"value\": V}, ...]")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Keys<T>, A::Error> {
                Keys::read_list(seq)
            }
        }
        deserializer.deserialize_seq(List(PhantomData))
    }
}

/// A value of the scene that may be keyed: its plain value, or keys.
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Animated<T> {
    /// The same value at every frame.
    Fixed(T),
    /// Keys at frame numbers.
    Keyed(Keys<T>),
}

impl<T: Default> Default for Animated<T> {
    fn default() -> Self {
        Animated::Fixed(T::default())
    }
}

impl<T> Animated<T> {
    /// The plain value, or the first key's: the value at the scene's first
    /// key (what commands without `--frame` see).
    pub fn first(&self) -> &T {
        match self {
            Animated::Fixed(v) => v,
            Animated::Keyed(k) => k.first(),
        }
    }

    /// Whether the value is keyed.
    pub fn is_keyed(&self) -> bool {
        matches!(self, Animated::Keyed(_))
    }
}

impl<T: Keyable> Animated<T> {
    /// The value at `frame`.
    pub fn at(&self, frame: f64) -> T {
        match self {
            Animated::Fixed(v) => v.clone(),
            Animated::Keyed(k) => k.at(frame),
        }
    }
}

// By hand rather than `untagged` (which the schema and the serialisation
// follow): a plain value is read straight from its array or number, with
// no buffering, and an error inside the keys names its place.
impl<'de, T: Keyable> Deserialize<'de> for Animated<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Value<T>(PhantomData<T>);
        impl<'de, T: Keyable> Visitor<'de> for Value<T> {
            type Value = Animated<T>;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "{} or keys {{\"keys\": [{{\"frame\": F, \"value\": V}}, ...]}}", T::EXPECTING)
            }

            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Animated<T>, A::Error> {
                T::deserialize(serde::de::value::SeqAccessDeserializer::new(seq)).map(Animated::Fixed)
            }

            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Animated<T>, E> {
                T::deserialize(v.into_deserializer()).map(Animated::Fixed)
            }

            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Animated<T>, E> {
                T::deserialize(v.into_deserializer()).map(Animated::Fixed)
            }

            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Animated<T>, E> {
                T::deserialize(v.into_deserializer()).map(Animated::Fixed)
            }

            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Animated<T>, A::Error> {
                keys_from_map(map).map(Animated::Keyed)
            }
        }
        deserializer.deserialize_any(Value(PhantomData))
    }
}

/// Spherical interpolation of two non-zero directions a fraction `t` of
/// the way (`0 < t < 1`): the unit vector turns at a constant rate in the
/// plane of the two, and the length goes linearly from `|a|` to `|b|`.
/// `None` when the two point in opposite directions (no one plane) or
/// either is zero or not finite.
pub fn slerp(a: &[f64; 3], b: &[f64; 3], t: f64) -> Option<[f64; 3]> {
    let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (la, lb) = (norm(a), norm(b));
    if !(la.is_finite() && lb.is_finite() && la > 0.0 && lb > 0.0) {
        return None;
    }
    let (ua, ub) = (a.map(|x| x / la), b.map(|x| x / lb));
    let dot: f64 = (0..3).map(|i| ua[i] * ub[i]).sum();
    let cross = [ua[1] * ub[2] - ua[2] * ub[1], ua[2] * ub[0] - ua[0] * ub[2], ua[0] * ub[1] - ua[1] * ub[0]];
    let sin = norm(&cross);
    // atan2 keeps the angle accurate near 0 and near 180°, where acos of the
    // dot product loses half the digits.
    let angle = sin.atan2(dot);
    let length = lerp(la, lb, t);
    if sin == 0.0 {
        // Parallel: the same direction, or opposite (no one plane to turn in).
        return (dot > 0.0).then(|| ua.map(|x| x * length));
    }
    // The component of `ub` orthogonal to `ua`, of length `sin`, divided
    // by it: the unit vector `ua` turns towards.
    let w = [0, 1, 2].map(|i| (ub[i] - dot * ua[i]) / sin);
    let (s, c) = (t * angle).sin_cos();
    Some([0, 1, 2].map(|i| (c * ua[i] + s * w[i]) * length))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn read<T: Keyable>(json: &str) -> Result<Animated<T>, String> {
        serde_json::from_str::<Animated<T>>(json).map_err(|e| e.to_string())
    }

    fn keys(pairs: &[(f64, f64)]) -> Keys<f64> {
        Keys { keys: pairs.iter().map(|&(frame, value)| Key { frame, value }).collect() }
    }

    #[test]
    fn values_are_held_outside_the_keys_exact_on_them_and_linear_between() {
        let k = keys(&[(2.0, 10.0), (6.0, 30.0), (7.0, -5.0)]);
        for (frame, want) in [
            (0.0, 10.0),
            (2.0, 10.0),
            (3.0, 15.0),
            (4.0, 20.0),
            (5.5, 27.5),
            (6.0, 30.0),
            (6.5, 12.5),
            (7.0, -5.0),
            (1e9, -5.0),
        ] {
            assert_eq!(k.at(frame), want, "frame {frame}");
        }
        assert_eq!(keys(&[(4.0, 1.0)]).at(0.0), 1.0);
        assert_eq!(keys(&[(4.0, 1.0)]).at(9.0), 1.0);
    }

    #[test]
    fn angles_interpolate_linearly_in_degrees() {
        // 0° to 90° over frames 1..=3: frame 2 is 45°, a quarter of the way 22.5°.
        let k = keys(&[(1.0, 0.0), (3.0, 90.0)]);
        assert_eq!(k.at(2.0), 45.0);
        assert_eq!(k.at(1.5), 22.5);
    }

    #[test]
    fn triples_interpolate_componentwise() {
        let k: Animated<[f64; 3]> =
            read(r#"{"keys": [{"frame": 0, "value": [0, 2, -4]}, {"frame": 4, "value": [4, 2, 4]}]}"#).unwrap();
        assert_eq!(k.at(1.0), [1.0, 2.0, -2.0]);
        assert_eq!(*k.first(), [0.0, 2.0, -4.0]);
    }

    #[test]
    fn plain_values_read_as_fixed() {
        assert_eq!(read::<f64>("2").unwrap(), Animated::Fixed(2.0));
        assert_eq!(read::<f64>("-2.5").unwrap(), Animated::Fixed(-2.5));
        assert_eq!(read::<[f64; 3]>("[1, 2, 3]").unwrap(), Animated::Fixed([1.0, 2.0, 3.0]));
        // Written back as read.
        for json in ["[1.0,2.0,3.0]", r#"{"keys":[{"frame":1.0,"value":[1.0,2.0,3.0]}]}"#] {
            assert_eq!(serde_json::to_string(&read::<[f64; 3]>(json).unwrap()).unwrap(), json);
        }
    }

    #[test]
    fn bad_keys_are_refused_with_a_reason() {
        for (json, want) in [
            (r#"{"keys": []}"#, "keys must not be empty"),
            (r#"{"keys": [{"frame": 2, "value": 1}, {"frame": 2, "value": 3}]}"#, "frame 2 follows frame 2"),
            (r#"{"keys": [{"frame": 3, "value": 1}, {"frame": 1, "value": 3}]}"#, "frame 1 follows frame 3"),
            (r#"{"keys": [{"frame": -1, "value": 1}]}"#, "between 0 and 4294967295, got -1"),
            (r#"{"keys": [{"frame": 4294967296, "value": 1}]}"#, "got 4294967296"),
            (r#"{"keys": [{"frame": 1}]}"#, "missing field `value`"),
            (r#"{"keys": [{"frame": 1, "value": 1, "ease": 2}]}"#, "unknown field `ease`"),
            (r#"{"kyes": []}"#, "unknown field `kyes`, expected `keys`"),
            (r#"{}"#, "missing field `keys`"),
            (r#"{"keys": {}}"#, "invalid type: map, expected a list of keys"),
            (r#""x""#, r#"expected a number or keys {"keys""#),
            (r#"{"keys": [{"frame": 1, "value": [1]}]}"#, "invalid type: sequence, expected f64"),
        ] {
            let got = read::<f64>(json).err().unwrap_or_default();
            assert!(got.contains(want), "{json}: {got}");
        }
        let got = read::<[f64; 3]>("[1, 2]").err().unwrap_or_default();
        assert!(got.contains("invalid length 2"), "{got}");
    }

    #[test]
    fn slerp_turns_at_a_constant_rate_and_scales_linearly() {
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-15);
        // -z to +x, lengths 1 to 3: a third of the way is 30° and length 5/3.
        let got = slerp(&[0.0, 0.0, -1.0], &[3.0, 0.0, 0.0], 1.0 / 3.0).unwrap();
        let (s, c) = (0.5, 3f64.sqrt() / 2.0);
        assert!(close(got, [s * 5.0 / 3.0, 0.0, -c * 5.0 / 3.0]), "{got:?}");
        // 170° apart: halfway is 85° from the first.
        let b = [(170f64).to_radians().cos(), (170f64).to_radians().sin(), 0.0];
        let got = slerp(&[1.0, 0.0, 0.0], &b, 0.5).unwrap();
        let want = [(85f64).to_radians().cos(), (85f64).to_radians().sin(), 0.0];
        assert!(close(got, want), "{got:?}");
        // The same direction: only the length changes.
        assert_eq!(slerp(&[0.0, 2.0, 0.0], &[0.0, 4.0, 0.0], 0.25).unwrap(), [0.0, 2.5, 0.0]);
        assert_eq!(slerp(&[0.0, 0.0, 1.0], &[0.0, 0.0, -2.0], 0.5), None);
        assert_eq!(slerp(&[0.0, 0.0, 0.0], &[0.0, 0.0, -2.0], 0.5), None);
    }
}
