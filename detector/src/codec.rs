//! A small binary codec for the detector's state, the embedded model and the
//! embedded threshold pools: straight-line code per type (no serde visitors,
//! no field-name strings), so the core wasm module carries a few KB of it
//! instead of serde + postcard's ~100 KB for the same types.
//!
//! The bytes are postcard's, exactly: integers as varints (LEB128, `usize`
//! as a 64-bit one), `u8` as one byte, `f64` as its 8 IEEE bits little-endian
//! (bit-exact, NaN included), `bool` as 0/1, `Option` as a 0/1 tag, enums as
//! a varint variant index, sequences as a varint length then the elements,
//! arrays, tuples, structs and nalgebra matrices (column-major) as their
//! elements in order. So snapshots keep their format, the shipped
//! `default_model.bin` and `default_pools.bin` read unchanged, and the
//! native tests hold every impl to serde's derive of the same struct (a
//! field missing here, or out of order, fails them).
//!
//! Reading never panics and never trusts a length: a sequence longer than
//! the bytes left is an error before anything is allocated. Reads do not
//! return a `Result` each: the [`Reader`] keeps the first error and yields
//! zeros, `false`, `None` and empty sequences after it, and the caller asks
//! once at the end ([`from_bytes`], [`Reader::finish`]). So a struct's
//! decode is straight-line code, with no unwinding of half-built fields at
//! every field.

use nalgebra::{Quaternion, SMatrix, UnitQuaternion};

/// Bytes that do not decode: what was expected and where.
#[derive(Clone, Debug, PartialEq)]
pub struct CodecError {
    /// What was wrong, with the byte offset.
    pub message: String,
}

impl core::fmt::Display for CodecError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Decoding cursor over a byte slice; remembers the first error.
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    error: Option<CodecError>,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, pos: 0, error: None }
    }

    /// The bytes not read yet (none after an error).
    pub fn rest(&self) -> &'a [u8] {
        self.bytes.get(self.pos..).unwrap_or(&[])
    }

    /// The first error met, if any: what was read since is zeros.
    pub fn finish(self) -> Result<(), CodecError> {
        self.error.map_or(Ok(()), Err)
    }

    /// Record an error (the first one counts) and stop reading: every later
    /// read sees no bytes left.
    // Out of line and cold: each read's error path is one call.
    #[cold]
    #[inline(never)]
    pub fn fail(&mut self, what: &str) {
        if self.error.is_none() {
            self.error = Some(CodecError { message: format!("{what} at byte {} of {}", self.pos, self.bytes.len()) });
        }
        self.pos = self.bytes.len();
    }

    /// The next `N` bytes (zeros, and an error, past the end).
    #[inline(never)]
    fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut b = [0u8; N];
        match self.bytes.get(self.pos..self.pos.saturating_add(N)) {
            Some(s) => {
                b.copy_from_slice(s);
                self.pos += N;
            }
            None => self.fail("unexpected end"),
        }
        b
    }

    fn byte(&mut self) -> u8 {
        self.array::<1>()[0]
    }

    /// An unsigned LEB128 varint of at most `bits` bits.
    #[inline(never)]
    fn varint(&mut self, bits: u32) -> u64 {
        let mut v = 0u64;
        let mut shift = 0u32;
        while self.error.is_none() {
            let b = self.byte();
            let low = u64::from(b & 0x7f);
            // `room`: the bits of the value this byte may still fill.
            let room = bits.saturating_sub(shift);
            if room == 0 || (room < 7 && low >> room != 0) {
                self.fail("varint too long");
                break;
            }
            v |= low << shift;
            if b & 0x80 == 0 {
                return v;
            }
            shift += 7;
        }
        0
    }

    /// A 0/1 byte (`bool`, `Option`'s tag).
    fn flag(&mut self, what: &str) -> bool {
        match self.byte() {
            0 => false,
            1 => true,
            _ => {
                self.fail(what);
                false
            }
        }
    }

    /// A sequence length, refused when longer than the bytes left (every
    /// element takes at least one byte), so a forged length cannot make the
    /// reader allocate more than the input's size in elements.
    #[inline(never)]
    pub fn len(&mut self) -> usize {
        let n = usize::decode(self);
        if n > self.bytes.len() - self.pos {
            self.fail(&format!("length {n} longer than the bytes left"));
            return 0;
        }
        n
    }

    /// An enum's variant index.
    pub fn variant(&mut self) -> u32 {
        u32::decode(self)
    }

    /// Record that variant `v` names no variant of `ty`.
    #[cold]
    #[inline(never)]
    pub fn bad_variant(&mut self, ty: &str, v: u32) {
        self.fail(&format!("{ty}: no variant {v}"));
    }
}

#[inline(never)]
fn put_varint(w: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        w.push((v as u8) | 0x80);
        v >>= 7;
    }
    w.push(v as u8);
}

#[inline(never)]
fn put_f64(w: &mut Vec<u8>, v: f64) {
    w.extend_from_slice(&v.to_bits().to_le_bytes());
}

/// A type that writes itself as bytes and reads itself back, exactly.
pub trait Codec: Sized {
    /// Append `self`'s bytes to `w`.
    fn encode(&self, w: &mut Vec<u8>);
    /// Read one value (the inverse of [`Codec::encode`]). On bad bytes the
    /// reader records the error and the value is zeros: check
    /// [`Reader::finish`] before using it.
    fn decode(r: &mut Reader<'_>) -> Self;
}

/// `value` as bytes.
#[cfg_attr(navguard_cold_size, optimize(size))]
pub fn to_bytes<T: Codec>(value: &T) -> Vec<u8> {
    let mut w = Vec::new();
    value.encode(&mut w);
    w
}

/// A value that must take `bytes` whole.
pub fn from_bytes<T: Codec>(bytes: &[u8]) -> Result<T, CodecError> {
    let mut r = Reader::new(bytes);
    let v = T::decode(&mut r);
    if r.error.is_none() && !r.rest().is_empty() {
        let n = r.rest().len();
        r.fail(&format!("{n} unexpected bytes after the value"));
    }
    r.finish().map(|()| v)
}

/// Largest output of [`unpack`]: far above the embedded data's size, so a
/// damaged input cannot make it allocate without bound.
const MAX_UNPACKED: usize = 1 << 24;

/// Bytes packed by [`pack`], unpacked: literal runs and back-references
/// (LZ77), each a varint length then the bytes, or a varint length and a
/// varint distance back into what is unpacked so far (the copy may overlap
/// itself). The embedded threshold pools ship packed: 21 KB of postcard
/// bytes, a third of it zeros and repeats, in 8 KB of the core wasm module.
/// Never panics: bad input is an error.
#[cfg_attr(navguard_cold_size, optimize(size))]
pub fn unpack(packed: &[u8]) -> Result<Vec<u8>, CodecError> {
    let mut r = Reader::new(packed);
    let mut out: Vec<u8> = Vec::new();
    while r.error.is_none() && !r.rest().is_empty() {
        // `len` checked that the literals are there.
        let n = r.len();
        let lit = r.rest().get(..n).unwrap_or(&[]);
        if lit.len() > MAX_UNPACKED - out.len() {
            r.fail("unpacked data too long");
            break;
        }
        out.extend_from_slice(lit);
        r.pos += lit.len();
        if r.rest().is_empty() {
            break;
        }
        let m = usize::decode(&mut r);
        let d = usize::decode(&mut r);
        if r.error.is_some() {
            break;
        }
        if d == 0 || d > out.len() || m > MAX_UNPACKED - out.len() {
            r.fail(&format!("back-reference {m} bytes from {d} back does not fit"));
            break;
        }
        let start = out.len() - d;
        for k in start..start + m {
            let b = out.get(k).copied().unwrap_or(0);
            out.push(b);
        }
    }
    r.finish().map(|()| out)
}

/// `bytes` packed for [`unpack`] (greedy LZ77 over 3-byte hash chains):
/// how the embedded pools were packed. Not needed to read them.
pub fn pack(bytes: &[u8]) -> Vec<u8> {
    use std::collections::HashMap;
    const MIN: usize = 4;
    let n = bytes.len();
    let mut w = Vec::new();
    let mut chains: HashMap<&[u8], Vec<usize>> = HashMap::new();
    let (mut i, mut lit) = (0, 0);
    while i < n {
        let key = bytes.get(i..i + 3);
        let mut best = (0, 0);
        if let Some(c) = key.and_then(|k| chains.get(k)) {
            for &j in c.iter().rev().take(64) {
                let l = bytes[i..].iter().zip(&bytes[j..]).take_while(|(a, b)| a == b).count();
                if l > best.0 {
                    best = (l, i - j);
                }
            }
        }
        let step = if best.0 >= MIN { best.0 } else { 1 };
        if best.0 >= MIN {
            (i - lit).encode(&mut w);
            w.extend_from_slice(&bytes[lit..i]);
            best.0.encode(&mut w);
            best.1.encode(&mut w);
            lit = i + step;
        }
        for k in i..i + step {
            if let Some(key) = bytes.get(k..k + 3) {
                chains.entry(key).or_default().push(k);
            }
        }
        i += step;
    }
    (n - lit).encode(&mut w);
    w.extend_from_slice(&bytes[lit..]);
    w
}

impl Codec for f64 {
    fn encode(&self, w: &mut Vec<u8>) {
        put_f64(w, *self);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        f64::from_bits(u64::from_le_bytes(r.array::<8>()))
    }
}

impl Codec for u8 {
    fn encode(&self, w: &mut Vec<u8>) {
        w.push(*self);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        r.byte()
    }
}

impl Codec for bool {
    fn encode(&self, w: &mut Vec<u8>) {
        w.push(u8::from(*self));
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        r.flag("bool not 0 or 1")
    }
}

impl Codec for u32 {
    fn encode(&self, w: &mut Vec<u8>) {
        put_varint(w, u64::from(*self));
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        r.varint(32) as u32
    }
}

impl Codec for u64 {
    fn encode(&self, w: &mut Vec<u8>) {
        put_varint(w, *self);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        r.varint(64)
    }
}

impl Codec for usize {
    fn encode(&self, w: &mut Vec<u8>) {
        put_varint(w, *self as u64);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let v = r.varint(64);
        usize::try_from(v).unwrap_or_else(|_| {
            r.fail(&format!("{v} does not fit a usize"));
            0
        })
    }
}

impl Codec for String {
    fn encode(&self, w: &mut Vec<u8>) {
        self.len().encode(w);
        w.extend_from_slice(self.as_bytes());
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let n = r.len();
        // `len` checked that the bytes are there.
        let bytes = r.rest().get(..n).unwrap_or(&[]);
        r.pos += bytes.len();
        match core::str::from_utf8(bytes) {
            Ok(s) => s.to_string(),
            Err(_) => {
                r.fail("string not UTF-8");
                String::new()
            }
        }
    }
}

impl<T: Codec> Codec for Option<T> {
    fn encode(&self, w: &mut Vec<u8>) {
        match self {
            None => w.push(0),
            Some(v) => {
                w.push(1);
                v.encode(w);
            }
        }
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        r.flag("option tag not 0 or 1").then(|| T::decode(r))
    }
}

impl<T: Codec> Codec for Vec<T> {
    fn encode(&self, w: &mut Vec<u8>) {
        self.len().encode(w);
        for v in self {
            v.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let n = r.len();
        (0..n).map(|_| T::decode(r)).collect()
    }
}

impl<T: Codec, const N: usize> Codec for [T; N] {
    fn encode(&self, w: &mut Vec<u8>) {
        for v in self {
            v.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        core::array::from_fn(|_| T::decode(r))
    }
}

impl<A: Codec, B: Codec> Codec for (A, B) {
    fn encode(&self, w: &mut Vec<u8>) {
        self.0.encode(w);
        self.1.encode(w);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let a = A::decode(r);
        (a, B::decode(r))
    }
}

impl<A: Codec, B: Codec, C: Codec> Codec for (A, B, C) {
    fn encode(&self, w: &mut Vec<u8>) {
        self.0.encode(w);
        self.1.encode(w);
        self.2.encode(w);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let a = A::decode(r);
        let b = B::decode(r);
        (a, b, C::decode(r))
    }
}

/// A fixed-size nalgebra matrix: its elements column-major (nalgebra's own
/// serde form).
impl<const R: usize, const C: usize> Codec for SMatrix<f64, R, C> {
    fn encode(&self, w: &mut Vec<u8>) {
        for v in self.as_slice() {
            v.encode(w);
        }
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        let mut m = Self::zeros();
        for v in m.as_mut_slice() {
            *v = f64::decode(r);
        }
        m
    }
}

/// A unit quaternion: its four coordinates `[i, j, k, w]`, taken as they
/// were (not renormalised, so the state comes back bit-exact).
impl Codec for UnitQuaternion<f64> {
    fn encode(&self, w: &mut Vec<u8>) {
        self.as_ref().coords.encode(w);
    }
    fn decode(r: &mut Reader<'_>) -> Self {
        UnitQuaternion::new_unchecked(Quaternion::from(SMatrix::<f64, 4, 1>::decode(r)))
    }
}

/// Implements [`Codec`] for a struct from its field list, in declaration
/// order. The impl destructures the struct without `..` and builds it with
/// a struct literal, so a field added to the struct and not to the list is
/// a compile error. Fields after `skip` are not written and come back as
/// `Default::default()` (caches rebuilt after a restore). A const generic
/// parameter is written `Name<const D: usize>`.
macro_rules! impl_codec {
    ($name:ident $(<const $g:ident: usize>)? { $($field:ident),* $(,)? } $(skip { $($skip:ident),* $(,)? })?) => {
        impl$(<const $g: usize>)? $crate::codec::Codec for $name$(<$g>)? {
            // `#[inline]`: compiled in the crate that snapshots and
            // restores (the core wasm module builds that one for size; this
            // crate is built for speed), and inlined only where that is
            // smaller. The codec is cold code.
            #[inline]
            #[allow(non_snake_case)] // the filter's `P`
            fn encode(&self, w: &mut Vec<u8>) {
                let $name { $($field,)* $($($skip: _,)*)? } = self;
                $($crate::codec::Codec::encode($field, w);)*
            }
            #[inline]
            fn decode(r: &mut $crate::codec::Reader<'_>) -> Self {
                // Struct literal fields are evaluated in the order written.
                $name {
                    $($field: $crate::codec::Codec::decode(r),)*
                    $($($skip: Default::default(),)*)?
                }
            }
        }
    };
}

/// Implements [`Codec`] for a fieldless enum: each variant with its index
/// (which must be its position in the declaration, as serde numbers them).
/// The match is exhaustive, so a new variant not listed is a compile error.
/// A bad index reads as the first variant, with the reader's error set.
macro_rules! impl_codec_enum {
    ($name:ident { $first:ident = $i0:literal $(, $variant:ident = $i:literal)* $(,)? }) => {
        impl $crate::codec::Codec for $name {
            #[inline] // see `impl_codec`
            fn encode(&self, w: &mut Vec<u8>) {
                let i: u32 = match self { $name::$first => $i0, $($name::$variant => $i,)* };
                $crate::codec::Codec::encode(&i, w);
            }
            #[inline] // see `impl_codec`
            fn decode(r: &mut $crate::codec::Reader<'_>) -> Self {
                match r.variant() {
                    $i0 => $name::$first,
                    $($i => $name::$variant,)*
                    v => {
                        r.bad_variant(stringify!($name), v);
                        $name::$first
                    }
                }
            }
        }
    };
}
pub(crate) use impl_codec;
pub(crate) use impl_codec_enum;

#[cfg(all(test, not(target_arch = "wasm32")))]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `v`'s bytes must be postcard's, and read back to the same bits.
    #[test]
    fn pack_and_unpack_round_trip() {
        let mut x: u64 = 1;
        let mut cases: Vec<Vec<u8>> = vec![vec![], vec![7], vec![0; 100], b"abcabcabcabcx".to_vec(), crate::methods::EMBEDDED_POOLS.to_vec()];
        for n in [1usize, 5, 64, 1000, 5000] {
            cases.push((0..n).map(|_| { x ^= x << 13; x ^= x >> 7; x ^= x << 17; (x % 5) as u8 }).collect());
        }
        for c in &cases {
            assert_eq!(&unpack(&pack(c)).unwrap(), c);
        }
    }

    #[test]
    fn bad_packed_bytes_are_an_error_not_a_panic() {
        for bad in [&[1u8][..], &[0, 5, 1], &[1, 9, 5, 2], &[0, 255, 255, 255, 255, 255, 255, 255, 255, 255, 1, 1]] {
            assert!(unpack(bad).is_err(), "{bad:?}");
        }
    }

    fn same_as_postcard<T: Codec + serde::Serialize + core::fmt::Debug>(v: &T) {
        let ours = to_bytes(v);
        assert_eq!(ours, postcard::to_allocvec(v).unwrap(), "{v:?}");
        let back: T = from_bytes(&ours).unwrap();
        assert_eq!(to_bytes(&back), ours);
    }

    proptest! {
        #[test]
        fn scalars_match_postcard(a in any::<u64>(), b in any::<u32>(), c in any::<usize>(), x in any::<f64>(), f in any::<bool>(), u in any::<u8>()) {
            same_as_postcard(&a);
            same_as_postcard(&b);
            same_as_postcard(&c);
            same_as_postcard(&x);
            same_as_postcard(&f);
            same_as_postcard(&u);
            same_as_postcard(&(Some(x), None::<f64>, [a, a]));
            same_as_postcard(&vec![(x, [b, b]); (u % 5) as usize]);
            same_as_postcard(&format!("é{a}"));
        }

        /// Any bytes: an error or a value, never a panic; never a length
        /// longer than the input accepted.
        #[test]
        fn garbage_is_an_error_not_a_panic(bytes in proptest::collection::vec(any::<u8>(), 0..64)) {
            let _ = from_bytes::<Vec<Vec<(f64, Option<u32>)>>>(&bytes);
            let _ = from_bytes::<String>(&bytes);
            let _ = from_bytes::<(u64, usize, bool)>(&bytes);
        }
    }

    #[test]
    fn matrices_and_quaternions_match_postcard() {
        let m = SMatrix::<f64, 3, 2>::from_fn(|i, j| (i * 10 + j) as f64 + 0.5);
        same_as_postcard(&m);
        let q = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3);
        same_as_postcard(&q);
        assert_eq!(from_bytes::<UnitQuaternion<f64>>(&to_bytes(&q)).unwrap(), q);
    }

    #[test]
    fn overlong_or_overflowing_input_is_refused() {
        // A length of 2^40 with three bytes after it: refused, not allocated.
        let mut b = Vec::new();
        put_varint(&mut b, 1 << 40);
        b.extend_from_slice(&[1, 2, 3]);
        let e = from_bytes::<Vec<u8>>(&b).unwrap_err();
        assert_eq!(e.message, format!("length {} longer than the bytes left at byte 6 of 9", 1u64 << 40));
        // u32 varints stop at 32 bits, u64 ones at 64.
        assert!(from_bytes::<u32>(&[0xff, 0xff, 0xff, 0xff, 0x0f]).is_ok());
        assert!(from_bytes::<u32>(&[0xff, 0xff, 0xff, 0xff, 0x1f]).is_err());
        assert!(from_bytes::<u64>(&[0xff; 9].iter().copied().chain([0x01]).collect::<Vec<_>>()).is_ok());
        assert!(from_bytes::<u64>(&[0xff; 9].iter().copied().chain([0x02]).collect::<Vec<_>>()).is_err());
        assert!(from_bytes::<u64>(&[0x80; 11]).is_err());
        assert!(from_bytes::<bool>(&[2]).is_err());
        assert!(from_bytes::<Option<u8>>(&[2, 0]).is_err());
        assert_eq!(from_bytes::<u8>(&[1, 2]).unwrap_err().message, "1 unexpected bytes after the value at byte 1 of 2");
        assert_eq!(from_bytes::<f64>(&[0; 7]).unwrap_err().message, "unexpected end at byte 0 of 7");
    }
}
