//! Decimal text to `f64`, correctly rounded: the same value, bit for bit,
//! and the same accepted and refused strings as `str::parse::<f64>`, which
//! the tests below hold it to (random and crafted inputs: every decimal
//! form of random doubles, the halfway points between neighbours, long and
//! exponent-heavy strings, and garbage).
//!
//! Why not std's: its Eisel-Lemire step carries a 10.4 KB table of 128-bit
//! powers of five, the largest piece of data in the core wasm module after
//! the embedded model, for one call in the CSV reader. Here the common
//! cells (up to 19 significant digits, a decimal exponent within ±19) are
//! exact in `f64` or `u128` arithmetic, and the rest is exact big-integer
//! arithmetic: slower, but only for strings no logger writes (20 or more
//! significant digits, or exponents past ±19), and never wrong.

use std::cmp::Ordering;

/// Significant digits kept; the rest only say whether anything nonzero
/// follows (a halfway point between two doubles has at most 767
/// significant digits, so past 800 only "above or at" matters).
const MAX_DIGITS: usize = 800;

/// `s` as an `f64`, or `None` where `str::parse::<f64>` would fail.
/// Grammar (std's): an optional sign, then `inf`, `infinity` or `nan` in
/// any case, or digits with an optional `.` (at least one digit on either
/// side), then an optional `e`/`E`, optional sign and at least one digit.
#[inline(never)]
pub fn parse_f64(s: &str) -> Option<f64> {
    let b = s.as_bytes();
    let (neg, b) = match b.first() {
        Some(b'-') => (true, &b[1..]),
        Some(b'+') => (false, &b[1..]),
        _ => (false, b),
    };
    if b.is_empty() {
        return None;
    }
    let v = match number(b) {
        Some(v) => v,
        None if b.eq_ignore_ascii_case(b"nan") => f64::NAN,
        None if b.eq_ignore_ascii_case(b"inf") || b.eq_ignore_ascii_case(b"infinity") => f64::INFINITY,
        None => return None,
    };
    Some(if neg { -v } else { v })
}

/// An unsigned decimal number (no sign, no inf/nan). One pass, with no
/// allocation, for up to 19 significant digits (every cell a logger
/// writes); longer ones are read again by [`number_long`].
fn number(b: &[u8]) -> Option<f64> {
    let mut m: u64 = 0;
    let mut n = 0; // significant digits in m
    let mut exp: i64 = 0; // value = m × 10^exp
    let mut any = false;
    let mut seen_dot = false;
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() {
            any = true;
            let d = c - b'0';
            if n == 19 {
                return number_long(b);
            }
            if d != 0 || n > 0 {
                m = 10 * m + u64::from(d);
                n += 1;
            }
            if seen_dot {
                exp -= 1;
            }
        } else if c == b'.' && !seen_dot {
            seen_dot = true;
        } else {
            break;
        }
        i += 1;
    }
    if !any {
        return None;
    }
    exp += exponent(&b[i..])?;
    if m == 0 {
        return Some(0.0);
    }
    while m % 10 == 0 {
        m /= 10;
        exp += 1;
        n -= 1;
    }
    Some(small(m, n, exp))
}

/// The exponent part (`e`/`E`, optional sign, digits) or nothing; `None`
/// for anything else. Saturates as std's does (it stops adding digits at
/// 0x10000).
fn exponent(b: &[u8]) -> Option<i64> {
    let Some((&first, rest)) = b.split_first() else { return Some(0) };
    if first != b'e' && first != b'E' {
        return None;
    }
    let (neg, digits) = match rest.split_first() {
        Some((b'-', d)) => (true, d),
        Some((b'+', d)) => (false, d),
        _ => (false, rest),
    };
    if digits.is_empty() {
        return None;
    }
    let mut e: i64 = 0;
    for &c in digits {
        if !c.is_ascii_digit() {
            return None;
        }
        if e < 0x10000 {
            e = 10 * e + i64::from(c - b'0');
        }
    }
    Some(if neg { -e } else { e })
}

/// A number of more than 19 significant digits: its digits kept (up to
/// MAX_DIGITS) for the exact path.
#[cold]
#[inline(never)]
fn number_long(b: &[u8]) -> Option<f64> {
    // Significant digits (leading zeros dropped), at most MAX_DIGITS of
    // them; `exp`: the power of ten of the last digit kept.
    let mut digits: Vec<u8> = Vec::new();
    let mut truncated = false;
    let mut exp: i64 = 0;
    let mut any = false;
    let mut i = 0;
    let mut seen_dot = false;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() {
            any = true;
            let d = c - b'0';
            if seen_dot {
                // a fraction digit: one more power of ten down, unless
                // dropped (then the kept digits' power stays)
                if digits.len() < MAX_DIGITS {
                    if d != 0 || !digits.is_empty() {
                        digits.push(d);
                    }
                    exp -= 1;
                } else {
                    truncated |= d != 0;
                }
            } else if digits.len() < MAX_DIGITS {
                if d != 0 || !digits.is_empty() {
                    digits.push(d);
                }
            } else {
                truncated |= d != 0;
                exp += 1;
            }
        } else if c == b'.' && !seen_dot {
            seen_dot = true;
        } else {
            break;
        }
        i += 1;
    }
    if !any {
        return None;
    }
    exp += exponent(&b[i..])?;
    // Trailing zeros of the kept digits go into the exponent.
    while digits.last() == Some(&0) {
        digits.pop();
        exp += 1;
    }
    if digits.len() <= 19 && !truncated {
        let m = digits.iter().fold(0u64, |m, &d| 10 * m + u64::from(d));
        return Some(if m == 0 { 0.0 } else { small(m, digits.len(), exp) });
    }
    Some(slow(&digits, exp, truncated))
}

/// Exact powers of ten as `f64` (10^22 is the largest).
fn pow10_f64(e: usize) -> f64 {
    let mut p = 1.0;
    for _ in 0..e {
        p *= 10.0;
    }
    p
}

/// `m` (nonzero, `n` digits, no trailing zero) × 10^`exp`, correctly
/// rounded.
fn small(m: u64, n: usize, exp: i64) -> f64 {
    // The value lies in [10^(lead-1), 10^lead).
    let lead = n as i64 + exp;
    if lead > 310 {
        return f64::INFINITY;
    }
    if lead < -323 {
        return 0.0;
    }
    // Clinger's fast path: both exact, one rounding.
    if m < 1 << 53 && (-22..=22).contains(&exp) {
        let p = pow10_f64(exp.unsigned_abs() as usize);
        return if exp < 0 { m as f64 / p } else { m as f64 * p };
    }
    if (0..=38).contains(&exp) {
        // m × 10^exp exact in u128 when it fits; `as` rounds to nearest.
        if let Some(v) = (m as u128).checked_mul(10u128.pow(exp as u32)) {
            return v as f64;
        }
    } else if (-19..0).contains(&exp) {
        // m / 10^-exp: m shifted to the top of 128 bits over a divisor
        // below 2^64 gives a quotient of 64 bits or more; a nonzero
        // remainder becomes a sticky low bit, below the rounding bit.
        let p = 10u64.pow((-exp) as u32);
        let z = m.leading_zeros();
        let (q, r) = div128(m << z, p);
        let q = q | u128::from(r != 0);
        return q as f64 * pow2(-(z as i32) - 64);
    }
    let mut digits = [0u8; 20];
    let mut k = 20;
    let mut v = m;
    while v > 0 {
        k -= 1;
        digits[k] = (v % 10) as u8;
        v /= 10;
    }
    slow(&digits[k..], exp, false)
}

/// (`hi` × 2^64) / `p` and its remainder, `p` nonzero: two 128-by-64-bit
/// steps of 32-bit digits each (Knuth's algorithm D), not a general u128
/// division.
fn div128(hi: u64, p: u64) -> (u128, u64) {
    let q1 = hi / p;
    let r1 = hi % p;
    // (r1 × 2^64) / p, r1 < p: the quotient fits 64 bits.
    let (q0, r0) = divlu(r1, 0, p);
    ((u128::from(q1) << 64) | u128::from(q0), r0)
}

/// (`u1` × 2^64 + `u0`) / `v` with `u1` < `v`: quotient and remainder
/// (Hacker's Delight, divlu).
fn divlu(u1: u64, u0: u64, v: u64) -> (u64, u64) {
    const B: u64 = 1 << 32;
    let s = v.leading_zeros();
    let v = v << s;
    let (vn1, vn0) = (v >> 32, v & (B - 1));
    let un32 = if s == 0 { u1 } else { (u1 << s) | (u0 >> (64 - s)) };
    let un10 = u0 << s;
    let (un1, un0) = (un10 >> 32, un10 & (B - 1));
    let mut q1 = un32 / vn1;
    let mut rhat = un32 - q1 * vn1;
    while q1 >= B || q1 * vn0 > B * rhat + un1 {
        q1 -= 1;
        rhat += vn1;
        if rhat >= B {
            break;
        }
    }
    let un21 = un32.wrapping_mul(B).wrapping_add(un1).wrapping_sub(q1.wrapping_mul(v));
    let mut q0 = un21 / vn1;
    rhat = un21 - q0 * vn1;
    while q0 >= B || q0 * vn0 > B * rhat + un0 {
        q0 -= 1;
        rhat += vn1;
        if rhat >= B {
            break;
        }
    }
    let r = (un21.wrapping_mul(B).wrapping_add(un0).wrapping_sub(q0.wrapping_mul(v))) >> s;
    (q1 * B + q0, r)
}

/// 2^e as an `f64`, for e in the normal range.
fn pow2(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// Exact: value = A / B with A = D × 10^max(exp,0), B = 10^max(-exp,0).
#[cold]
#[inline(never)]
fn slow(digits: &[u8], exp: i64, truncated: bool) -> f64 {
    let mut a = Big::from_digits(digits);
    let mut b = Big(vec![1]);
    if exp >= 0 {
        a.mul_pow10(exp as usize);
    } else {
        b.mul_pow10((-exp) as usize);
    }
    // k = floor(log2(A / B)): a - b or one less (a, b the bit lengths).
    let d = a.bits() as i64 - b.bits() as i64;
    let ge = if d >= 0 { a.cmp(&b.shl(d as usize)) } else { a.shl((-d) as usize).cmp(&b) };
    let k = if ge == Ordering::Less { d - 1 } else { d };
    if k > 1023 {
        return f64::INFINITY;
    }
    if k < -1076 {
        return 0.0;
    }
    // Scale so that the quotient is the 53-bit mantissa (or, below the
    // normal range, the subnormal's units of 2^-1074).
    let t = if k >= -1022 { 52 - k } else { 1074 };
    let mut r = if t > 0 { a.shl(t as usize) } else { a };
    let mut bs = if t < 0 { b.shl((-t) as usize) } else { b };
    // Long division: m < 2^53, so 54 quotient bits at most.
    let mut m: u64 = 0;
    let mut sh = bs.shl(53);
    for i in (0..=53).rev() {
        if r.cmp(&sh) != Ordering::Less {
            r.sub(&sh);
            m |= 1 << i;
        }
        sh.shr1();
    }
    // Round half to even on the remainder (truncated digits: above half).
    r.shl1();
    bs.trim();
    match r.cmp(&bs) {
        Ordering::Greater => m += 1,
        Ordering::Equal if truncated || m & 1 == 1 => m += 1,
        _ => {}
    }
    if k >= -1022 {
        let mut k = k;
        if m == 1 << 53 {
            m = 1 << 52;
            k += 1;
        }
        if k > 1023 {
            return f64::INFINITY;
        }
        f64::from_bits((((k + 1023) as u64) << 52) | (m & ((1 << 52) - 1)))
    } else {
        // m up to 2^52 inclusive: 2^52 is the bit pattern of MIN_POSITIVE.
        f64::from_bits(m)
    }
}

/// An unsigned big integer, 32-bit limbs, least significant first.
struct Big(Vec<u32>);

impl Big {
    fn from_digits(digits: &[u8]) -> Big {
        let mut x = Big(Vec::with_capacity(digits.len() / 9 + 1));
        for chunk in digits.chunks(9) {
            let v = chunk.iter().fold(0u32, |v, &d| 10 * v + u32::from(d));
            x.mul_add(10u32.pow(chunk.len() as u32), v);
        }
        x
    }

    /// self = self × m + add.
    fn mul_add(&mut self, m: u32, add: u32) {
        let mut carry = u64::from(add);
        for l in self.0.iter_mut() {
            let v = u64::from(*l) * u64::from(m) + carry;
            *l = v as u32;
            carry = v >> 32;
        }
        if carry != 0 {
            self.0.push(carry as u32);
        }
    }

    fn mul_pow10(&mut self, mut e: usize) {
        while e >= 9 {
            self.mul_add(1_000_000_000, 0);
            e -= 9;
        }
        if e > 0 {
            self.mul_add(10u32.pow(e as u32), 0);
        }
    }

    fn trim(&mut self) {
        while self.0.last() == Some(&0) {
            self.0.pop();
        }
    }

    fn bits(&self) -> usize {
        match self.0.iter().rposition(|&l| l != 0) {
            Some(i) => 32 * i + 32 - self.0[i].leading_zeros() as usize,
            None => 0,
        }
    }

    fn shl(&self, n: usize) -> Big {
        let (w, s) = (n / 32, (n % 32) as u32);
        let mut out = vec![0u32; w];
        let mut carry = 0u32;
        for &l in &self.0 {
            if s == 0 {
                out.push(l);
            } else {
                out.push((l << s) | carry);
                carry = l >> (32 - s);
            }
        }
        if carry != 0 {
            out.push(carry);
        }
        let mut x = Big(out);
        x.trim();
        x
    }

    fn shl1(&mut self) {
        *self = self.shl(1);
    }

    fn shr1(&mut self) {
        let mut carry = 0u32;
        for l in self.0.iter_mut().rev() {
            let v = *l;
            *l = (v >> 1) | (carry << 31);
            carry = v & 1;
        }
        self.trim();
    }

    /// Compare, ignoring high zero limbs.
    fn cmp(&self, other: &Big) -> Ordering {
        let (a, b) = (self.len(), other.len());
        if a != b {
            return a.cmp(&b);
        }
        for i in (0..a).rev() {
            match self.0[i].cmp(&other.0[i]) {
                Ordering::Equal => {}
                o => return o,
            }
        }
        Ordering::Equal
    }

    /// Limbs without the high zero ones.
    fn len(&self) -> usize {
        self.0.iter().rposition(|&l| l != 0).map_or(0, |i| i + 1)
    }

    /// self -= other (self ≥ other).
    fn sub(&mut self, other: &Big) {
        let mut borrow = 0i64;
        for i in 0..self.0.len() {
            let v = i64::from(self.0[i]) - i64::from(other.0.get(i).copied().unwrap_or(0)) - borrow;
            self.0[i] = v as u32;
            borrow = i64::from(v < 0);
        }
        self.trim();
    }
}

/// Add to [`Big`] what printing needs.
impl Big {
    fn from_u64(v: u64) -> Big {
        let mut x = Big(vec![v as u32, (v >> 32) as u32]);
        x.trim();
        x
    }

    fn is_zero(&self) -> bool {
        self.len() == 0
    }

    /// self + other.
    fn plus(&self, other: &Big) -> Big {
        let n = self.0.len().max(other.0.len());
        let mut out = Vec::with_capacity(n + 1);
        let mut carry = 0u64;
        for i in 0..n {
            let v = u64::from(self.0.get(i).copied().unwrap_or(0)) + u64::from(other.0.get(i).copied().unwrap_or(0)) + carry;
            out.push(v as u32);
            carry = v >> 32;
        }
        if carry != 0 {
            out.push(carry as u32);
        }
        Big(out)
    }

    /// self /= d (d nonzero), rounding down.
    fn div_small(&mut self, d: u32) {
        let mut rem = 0u64;
        for l in self.0.iter_mut().rev() {
            let v = (rem << 32) | u64::from(*l);
            *l = (v / u64::from(d)) as u32;
            rem = v % u64::from(d);
        }
        self.trim();
    }

    /// The next digit: self / scale (below 10), self keeping the remainder.
    fn digit(&mut self, scale: &Big) -> u8 {
        let mut d = 0;
        while self.cmp(scale) != Ordering::Less {
            self.sub(scale);
            d += 1;
        }
        d
    }
}

// Printing: `{}`, `{:e}` and `{:.N}` of an f64, the same text as std's
// (std's own exact algorithm, Dragon4, ported from core::num::flt2dec over
// the `Big` above), without std's float-printing code and tables in the
// core wasm module: about 10 KB there for a few messages and metadata
// values. The tests hold every form to std's over random and crafted
// doubles.

/// std's `Decoded`: the value is `mant` × 2^`exp`; the rounding interval
/// reaches `minus` below and `plus` above (same scale), its ends included
/// when `inclusive`.
struct Decoded {
    mant: u64,
    minus: u64,
    plus: u64,
    exp: i32,
    inclusive: bool,
}

/// A finite nonzero `x` decoded as std decodes it (`flt2dec::decode`).
fn decode(x: f64) -> Decoded {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1 << 52) - 1);
    let (mant, exp) = if biased == 0 { (frac << 1, -1075) } else { (frac | (1 << 52), biased - 1075) };
    let inclusive = mant & 1 == 0;
    if biased == 0 {
        Decoded { mant, minus: 1, plus: 1, exp, inclusive }
    } else if mant == 1 << 52 {
        Decoded { mant: mant << 2, minus: 1, plus: 2, exp: exp - 2, inclusive }
    } else {
        Decoded { mant: mant << 1, minus: 1, plus: 1, exp: exp - 1, inclusive }
    }
}

/// std's `estimate_scaling_factor`.
fn estimate_k(mant: u64, exp: i32) -> i32 {
    let nbits = 64 - (mant - 1).leading_zeros() as i64;
    (((nbits + i64::from(exp)) * 1_292_913_986) >> 32) as i32
}

/// std's `round_up` on decimal digits (ASCII).
fn round_up(d: &mut [u8]) -> Option<u8> {
    match d.iter().rposition(|&c| c != b'9') {
        Some(i) => {
            d[i] += 1;
            d[i + 1..].iter_mut().for_each(|c| *c = b'0');
            None
        }
        None if d.is_empty() => Some(b'1'),
        None => {
            d[0] = b'1';
            d[1..].iter_mut().for_each(|c| *c = b'0');
            Some(b'0')
        }
    }
}

/// `mant` × 2^`exp` as (mant, scale) Bigs, the power of two on one side.
fn scaled(mant: u64, exp: i32) -> (Big, Big) {
    let (mut m, mut s) = (Big::from_u64(mant), Big(vec![1]));
    if exp < 0 {
        s = s.shl((-exp) as usize);
    } else {
        m = m.shl(exp as usize);
    }
    (m, s)
}

/// Dragon4's shortest digits (std's `dragon::format_shortest`): the
/// digits and the decimal exponent k (value = 0.d1d2... × 10^k).
fn shortest(d: &Decoded) -> (Vec<u8>, i32) {
    let rounding = if d.inclusive { Ordering::Greater } else { Ordering::Equal };
    let mut k = estimate_k(d.mant + d.plus, d.exp);
    let (mut mant, mut scale) = scaled(d.mant, d.exp);
    let (mut minus, _) = scaled(d.minus, d.exp.max(0));
    let (mut plus, _) = scaled(d.plus, d.exp.max(0));
    if k >= 0 {
        scale.mul_pow10(k as usize);
    } else {
        for b in [&mut mant, &mut minus, &mut plus] {
            b.mul_pow10((-k) as usize);
        }
    }
    if scale.cmp(&mant.plus(&plus)) < rounding {
        k += 1;
    } else {
        for b in [&mut mant, &mut minus, &mut plus] {
            b.mul_add(10, 0);
        }
    }
    let mut buf = Vec::new();
    let (mut down, mut up);
    loop {
        buf.push(b'0' + mant.digit(&scale));
        down = mant.cmp(&minus) < rounding;
        up = scale.cmp(&mant.plus(&plus)) < rounding;
        if down || up {
            break;
        }
        for b in [&mut mant, &mut minus, &mut plus] {
            b.mul_add(10, 0);
        }
    }
    if up && (!down || mant.shl(1).cmp(&scale) != Ordering::Less) {
        if let Some(c) = round_up(&mut buf) {
            buf.push(c);
            k += 1;
        }
    }
    (buf, k)
}

/// Dragon4's exact digits down to the decimal position `limit` (std's
/// `dragon::format_exact` with a buffer of `maxlen`).
fn exact(d: &Decoded, maxlen: usize, limit: i32) -> (Vec<u8>, i32) {
    let mut k = estimate_k(d.mant, d.exp);
    let (mut mant, mut scale) = scaled(d.mant, d.exp);
    if k >= 0 {
        scale.mul_pow10(k as usize);
    } else {
        mant.mul_pow10((-k) as usize);
    }
    // scale / (2 × 10^maxlen), rounded down step by step as std's does
    let mut half = Big(scale.0.clone());
    let mut n = maxlen;
    while n > 9 {
        half.div_small(1_000_000_000);
        n -= 9;
    }
    half.div_small(10u32.pow(n as u32) << 1);
    if half.plus(&mant).cmp(&scale) != Ordering::Less {
        k += 1;
    } else {
        mant.mul_add(10, 0);
    }
    let mut len = if k < limit {
        0
    } else if ((k - limit) as usize) < maxlen {
        (k - limit) as usize
    } else {
        maxlen
    };
    let mut buf = Vec::with_capacity(len + 1);
    for _ in 0..len {
        if mant.is_zero() {
            buf.resize(len, b'0');
            return (buf, k);
        }
        buf.push(b'0' + mant.digit(&scale));
        mant.mul_add(10, 0);
    }
    scale.mul_add(5, 0);
    let order = mant.cmp(&scale);
    if order == Ordering::Greater || (order == Ordering::Equal && len > 0 && buf[len - 1] & 1 == 1) {
        if let Some(c) = round_up(&mut buf) {
            k += 1;
            if k > limit && len < maxlen {
                buf.push(c);
                len += 1;
            }
        }
    }
    buf.truncate(len);
    (buf, k)
}

/// std's `digits_to_dec_str`.
fn dec_str(out: &mut String, buf: &[u8], exp: i32, frac_digits: usize) {
    let zeros = |out: &mut String, n: usize| out.extend(core::iter::repeat_n('0', n));
    let text = |out: &mut String, b: &[u8]| b.iter().for_each(|&c| out.push(char::from(c)));
    if exp <= 0 {
        let minus_exp = (-exp) as usize;
        out.push_str("0.");
        zeros(out, minus_exp);
        text(out, buf);
        if frac_digits > buf.len() && frac_digits - buf.len() > minus_exp {
            zeros(out, frac_digits - buf.len() - minus_exp);
        }
    } else {
        let exp = exp as usize;
        if exp < buf.len() {
            text(out, &buf[..exp]);
            out.push('.');
            text(out, &buf[exp..]);
            if frac_digits > buf.len() - exp {
                zeros(out, frac_digits - (buf.len() - exp));
            }
        } else {
            text(out, buf);
            zeros(out, exp - buf.len());
            if frac_digits > 0 {
                out.push('.');
                zeros(out, frac_digits);
            }
        }
    }
}

/// The sign, and NaN, infinities and zeros as std writes them; `None` for
/// a finite nonzero value (what is left to write).
fn special(out: &mut String, x: f64, zero: &str) -> Option<()> {
    if x.is_nan() {
        out.push_str("NaN");
        return Some(());
    }
    if x.is_sign_negative() {
        out.push('-');
    }
    if x.is_infinite() {
        out.push_str("inf");
        return Some(());
    }
    if x == 0.0 {
        out.push_str(zero);
        return Some(());
    }
    None
}

/// `{}` of an `f64`, as std writes it (the shortest digits that read back
/// as the same value, no exponent).
pub struct Shortest(pub f64);

impl core::fmt::Display for Shortest {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        #[cfg(feature = "compact-floats")]
        return f.write_str(&shortest_text(self.0));
        #[cfg(not(feature = "compact-floats"))]
        return write!(f, "{}", self.0);
    }
}

/// [`Shortest`]'s text, by the port.
pub fn shortest_text(x: f64) -> String {
    let mut out = String::new();
    if special(&mut out, x, "0").is_none() {
        let (buf, k) = shortest(&decode(x));
        dec_str(&mut out, &buf, k, 0);
    }
    out
}

/// `{:e}` of an `f64`, as std writes it (the shortest digits, `1.5e-7`).
pub struct Sci(pub f64);

impl core::fmt::Display for Sci {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        #[cfg(feature = "compact-floats")]
        return f.write_str(&sci_text(self.0));
        #[cfg(not(feature = "compact-floats"))]
        return write!(f, "{:e}", self.0);
    }
}

/// [`Sci`]'s text, by the port.
pub fn sci_text(x: f64) -> String {
    let mut out = String::new();
    if special(&mut out, x, "0e0").is_none() {
        let (buf, k) = shortest(&decode(x));
        out.push(char::from(buf[0]));
        if buf.len() > 1 {
            out.push('.');
            buf[1..].iter().for_each(|&c| out.push(char::from(c)));
        }
        out.push('e');
        out.push_str(&(k - 1).to_string());
    }
    out
}

/// `{:.N}` of an `f64` (N = `.1`), as std writes it (exact digits rounded
/// half to even at the N-th decimal).
pub struct Fixed(pub f64, pub usize);

impl core::fmt::Display for Fixed {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        #[cfg(feature = "compact-floats")]
        return f.write_str(&fixed_text(self.0, self.1));
        #[cfg(not(feature = "compact-floats"))]
        return write!(f, "{:.*}", self.1, self.0);
    }
}

/// [`Fixed`]'s text, by the port.
pub fn fixed_text(x: f64, frac_digits: usize) -> String {
    let mut out = String::new();
    let zero = |out: &mut String| {
        out.push('0');
        if frac_digits > 0 {
            out.push('.');
            out.extend(core::iter::repeat_n('0', frac_digits));
        }
    };
    let mut sign = String::new();
    if special(&mut sign, x, "").is_some() {
        out.push_str(&sign);
        if x == 0.0 {
            zero(&mut out);
        }
    } else {
        out.push_str(&sign);
        let d = decode(x);
        let maxlen = 21 + ((if d.exp < 0 { -12 } else { 5 } * d.exp) as usize >> 4);
        let limit = if frac_digits < 0x8000 { -(frac_digits as i32) } else { i32::from(i16::MIN) };
        let (buf, k) = exact(&d, maxlen, limit);
        if k <= limit {
            zero(&mut out);
        } else {
            dec_str(&mut out, &buf, k, frac_digits);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::parse_f64;

    use crate::TestRng as Rng;

    /// Same result as std's, bit for bit (NaN's sign included), or both refuse.
    fn same(s: &str) -> bool {
        let ours = parse_f64(s).map(f64::to_bits);
        let std = s.parse::<f64>().ok().map(f64::to_bits);
        assert_eq!(ours, std, "{s:?}: ours {:?}, std {:?}", parse_f64(s), s.parse::<f64>().ok());
        std.is_some()
    }

    #[test]
    fn crafted_strings_match_std() {
        let cases = [
            "0", "-0", "+0", "0.0", ".0", "0.", ".", "", "+", "-", "e5", "1e", "1e+", "1e-", "1E5", "1e+5", "1e-5", "1.e5", ".5e1",
            "1..2", "1.2.3", "--1", "+-1", " 1", "1 ", "1e5.5", "0x10", "1_000", "inf", "-inf", "+inf", "INF", "Infinity", "-infinity",
            "infinit", "infinityy", "nan", "NaN", "-nan", "+NAN", "nana", "in", "na", "1.7976931348623157e308", "1.7976931348623158e308",
            "1.7976931348623159e308", "1.797693134862315807e308", "1.7976931348623157081e308", "2e308", "1e309", "4.9e-324",
            "4.940656458412465441765687928682213723651e-324", "2.4703282292062327e-324", "2.4703282292062328e-324",
            "2.470328229206232720882538e-324", "2.2250738585072011e-308", "2.2250738585072012e-308", "2.2250738585072014e-308",
            "1e-400", "1e-324", "3e-324", "0.1", "0.2", "0.3", "123456789012345678901234567890", "9007199254740993",
            "9007199254740992.5", "9007199254740993.0000000000000000000001", "1e23", "8.98846567431158e307", "0.000000000000000000000000001",
            "47.39774190000001", "8.5", "-122.1234567", "1e19", "12345678901234567890", "18446744073709551615", "18446744073709551616",
            "1e-19", "1e-20", "1e-21", "1e-22", "1e-23", "123456789012345678e-30", "1e65535", "1e65536", "1e655359", "1e999999999999",
            "1e-999999999999", "0e999999999999", "0.0000e-99999", "00000000000000000000001.5", "1.00000000000000000000000000000000000001",
        ];
        for s in cases {
            same(s);
        }
        // Long strings: digits past the cap, zeros before and after.
        let long = format!("1.{}1", "0".repeat(900));
        same(&long);
        same(&format!("0.{}1e{}", "0".repeat(2000), 1990));
        same(&format!("{}e-{}", "9".repeat(1000), 700));
        same(&format!("1{}e-1000", "0".repeat(1300)));
        // Halfway between 1 and the next double, then a 1 far past the cap.
        same(&format!("1.00000000000000011102230246251565404236316680908203125{}1", "0".repeat(900)));
        same("1.00000000000000011102230246251565404236316680908203125");
        same("1.00000000000000011102230246251565404236316680908203124");
        // The exponent saturates as std's does.
        same(&format!("0.{}1e70000", "0".repeat(69990)));
    }

    #[test]
    fn every_form_of_random_doubles_and_their_halfway_points_match_std() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut parsed = 0;
        for i in 0..200_000 {
            let x = match i % 4 {
                // any finite double
                0 => f64::from_bits(rng.next() & !(0x7ff << 52) | (rng.below(2047) << 52)),
                // log-like magnitudes
                1 => (rng.below(2_000_000) as f64 - 1e6) * 10f64.powi(rng.below(12) as i32 - 8),
                2 => f64::from_bits(rng.below(1 << 60)),
                _ => f64::from_bits(rng.below(1 << 53)),
            };
            for s in [format!("{x}"), format!("{x:e}"), format!("{x:.3}"), format!("{x:.17e}"), format!("{x:.25e}"), format!("{x:.0}")] {
                parsed += usize::from(same(&s));
            }
            // The exact halfway point to the next double up, and just off it.
            if x.is_finite() && x > 0.0 && i % 8 == 0 {
                let up = f64::from_bits(x.to_bits() + 1);
                if up.is_finite() {
                    let h = halfway(x);
                    same(&h);
                    let (mant, ex) = h.split_once('e').map_or((h.as_str(), String::new()), |(a, b)| (a, format!("e{b}")));
                    // a hair above (a 1 appended) and below (the last digit one less)
                    same(&format!("{mant}.1{ex}").replacen("..", ".", 1));
                    let last = mant.as_bytes()[mant.len() - 1];
                    if last > b'0' {
                        same(&format!("{}{}{ex}", &mant[..mant.len() - 1], char::from(last - 1)));
                    }
                }
            }
        }
        assert!(parsed > 1_000_000, "{parsed}");
    }

    /// The exact decimal expansion of the midpoint of `x` (> 0) and the next
    /// double up: (2m + 1) × 2^(e - 1), in base-10^9 limbs.
    fn halfway(x: f64) -> String {
        let bits = x.to_bits();
        let (e, m) = ((bits >> 52) as i64, bits & ((1 << 52) - 1));
        let (m, e) = if e == 0 { (m, -1074) } else { (m | (1 << 52), e - 1075) };
        let n = 2 * m + 1; // × 2^(e - 1)
        let e = e - 1;
        let mut limbs: Vec<u64> = vec![n % 1_000_000_000, n / 1_000_000_000 % 1_000_000_000, n / 1_000_000_000_000_000_000];
        let mul = |l: &mut Vec<u64>, k: u64| {
            let mut carry = 0;
            for x in l.iter_mut() {
                let v = *x * k + carry;
                *x = v % 1_000_000_000;
                carry = v / 1_000_000_000;
            }
            while carry > 0 {
                l.push(carry % 1_000_000_000);
                carry /= 1_000_000_000;
            }
        };
        // n × 2^e for e ≥ 0; n × 5^-e (× 10^e) for e < 0
        let (base, chunk, mut left) = if e >= 0 { (2u64, 1u64 << 28, e) } else { (5, 244_140_625, -e) };
        let per = if e >= 0 { 28 } else { 12 };
        while left >= per {
            mul(&mut limbs, chunk);
            left -= per;
        }
        mul(&mut limbs, base.pow(left as u32));
        while limbs.len() > 1 && limbs.last() == Some(&0) {
            limbs.pop();
        }
        let mut s = limbs.last().unwrap().to_string();
        for l in limbs.iter().rev().skip(1) {
            s += &format!("{l:09}");
        }
        if e >= 0 {
            s
        } else {
            format!("{s}e{e}")
        }
    }

    #[test]
    fn div128_is_u128_division() {
        let mut rng = Rng(7);
        for i in 0..1_000_000u64 {
            let hi = rng.next() >> (i % 64);
            let p = (rng.next() >> (rng.below(64))).max(1);
            let a = u128::from(hi) << 64;
            assert_eq!(super::div128(hi, p), (a / u128::from(p), (a % u128::from(p)) as u64), "{hi} {p}");
        }
    }

    #[test]
    fn random_strings_match_std() {
        let mut rng = Rng(42);
        let alphabet = b"0123456789000.eE+-naifty";
        let mut accepted = 0;
        for _ in 0..300_000 {
            let len = 1 + rng.below(30) as usize;
            let s: String = (0..len).map(|_| char::from(alphabet[rng.below(alphabet.len() as u64) as usize])).collect();
            accepted += usize::from(same(&s));
            // a well-formed number of random digits and exponent
            let digits: String = (0..1 + rng.below(40)).map(|_| char::from(b'0' + rng.below(10) as u8)).collect();
            let dot = rng.below(digits.len() as u64 + 1) as usize;
            let s = format!("{}.{}e{}", &digits[..dot], &digits[dot..], rng.below(700) as i64 - 350);
            accepted += usize::from(same(&s));
        }
        assert!(accepted > 300_000, "{accepted}");
    }

    /// Every form we print, against std's.
    fn same_text(x: f64) {
        use super::{fixed_text, sci_text, shortest_text, Fixed, Sci, Shortest};
        assert_eq!(shortest_text(x), format!("{x}"), "{{}} of {:e} ({:#x})", x, x.to_bits());
        assert_eq!(sci_text(x), format!("{x:e}"), "{{:e}} of {x:e}");
        for p in [0, 1, 2, 3, 4, 6, 9, 17, 30] {
            assert_eq!(fixed_text(x, p), format!("{x:.p$}"), "{{:.{p}}} of {x:e} ({:#x})", x.to_bits());
            assert_eq!(Fixed(x, p).to_string(), format!("{x:.p$}"));
        }
        assert_eq!((Shortest(x).to_string(), Sci(x).to_string()), (format!("{x}"), format!("{x:e}")));
    }

    #[test]
    fn printing_matches_std() {
        for x in [0.0, -0.0, 1.0, -1.0, 0.5, 1.5, 2.5, -2.5, 0.25, 0.35, 0.125, 9.5, 99.95, 0.1, 0.2, 0.3, 1e21, 1e22, 1e23, 1e-7, 123.456,
            f64::NAN, -f64::NAN, f64::INFINITY, f64::NEG_INFINITY, f64::MAX, f64::MIN, f64::MIN_POSITIVE, -f64::MIN_POSITIVE,
            f64::from_bits(1), f64::from_bits(2), f64::from_bits(0x000f_ffff_ffff_ffff), f64::EPSILON, 5e-324, 0.0049999, 0.0005, 0.00051,
            1234.5, 0.9999999, 9.9999999e9, 47.3977419, 8.5, 257.926, 0.0045, 0.015] {
            same_text(x);
        }
        let mut rng = Rng(0x5eed);
        for i in 0..60_000 {
            let x = match i % 5 {
                0 => f64::from_bits(rng.next()),
                // powers of two: the asymmetric interval
                1 => f64::from_bits(rng.below(2046) << 52) * if rng.below(2) == 0 { 1.0 } else { -1.0 },
                2 => (rng.below(2_000_000) as f64 - 1e6) * 10f64.powi(rng.below(12) as i32 - 8),
                3 => f64::from_bits(rng.below(1 << 53)),
                // exact ties at a few decimals
                _ => (rng.below(100_000) as f64 + 0.5) / 10f64.powi(rng.below(4) as i32),
            };
            same_text(x);
        }
    }
}
