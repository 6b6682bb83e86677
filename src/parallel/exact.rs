//! Sums whose result does not depend on the order of their terms: a long fixed-point
//! accumulator (Kulisch's "exact dot product" register) that holds any sum of f64 values
//! without rounding, rounded once when read.
//!
//! Why: body loads, probes and port samples add up a contribution per particle. In a
//! distributed run which rank owns a particle, and in what order a rank holds its particles,
//! depend on the decomposition's history (migrations, rebalances, a restored state split
//! anew); a floating-point sum would change in its last bits with them. With these sums the
//! loads a master reads are the same bits on any number of ranks and after any rollback, as
//! the particles themselves are (`parallel`), and a rank's partial sum merges with the
//! others' exactly.
//!
//! Representation: an f64 is m·2^(e−1074) with an integer m < 2^53 and 0 ≤ e ≤ 2045, so
//! every finite f64 is an integer multiple of 2^−1074 below 2^2098. The register holds
//! that integer in 32-bit digits kept in i64 slots (carry-save: up to 2^30 additions before
//! the carries must be passed on). Infinities and NaN are summed apart, as IEEE would.

/// Bits per digit.
const DIGIT: u32 = 32;
/// Digits: 2098 bits of value, plus room for the carries of 2^30 additions and the sign.
const DIGITS: usize = 67;
/// Additions between two carry passes (each adds < 2^32 to a digit; an i64 holds 2^62).
const CARRY_EVERY: u32 = 1 << 30;

#[derive(Clone, Debug, PartialEq)]
pub struct ExactSum {
    digits: [i64; DIGITS],
    pending: u32,
    /// The sum of the non-finite terms (0 while there are none).
    special: f64,
}

impl Default for ExactSum {
    fn default() -> Self {
        Self {
            digits: [0; DIGITS],
            pending: 0,
            special: 0.0,
        }
    }
}

impl ExactSum {
    /// Bytes of [`Self::to_bytes`].
    pub const BYTES: usize = DIGITS * 8 + 8;

    pub fn new() -> Self {
        Self::default()
    }

    /// Add `x` exactly.
    pub fn add(&mut self, x: f64) {
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7ff) as usize;
        if exponent == 0x7ff {
            self.special += x;
            return;
        }
        let fraction = bits & ((1u64 << 52) - 1);
        // x = m · 2^(at − 1074)
        let (m, at) = if exponent == 0 {
            (fraction, 0)
        } else {
            (fraction | (1u64 << 52), exponent - 1)
        };
        if m == 0 {
            return;
        }
        let wide = (m as u128) << (at % DIGIT as usize);
        let k = at / DIGIT as usize;
        let negative = bits >> 63 == 1;
        for j in 0..3 {
            let d = ((wide >> (DIGIT as usize * j)) & 0xffff_ffff) as i64;
            self.digits[k + j] += if negative { -d } else { d };
        }
        self.pending += 1;
        if self.pending >= CARRY_EVERY {
            self.carry();
        }
    }

    /// Add another register's sum exactly.
    pub fn merge(&mut self, other: &ExactSum) {
        self.carry();
        let mut o = other.clone();
        o.carry();
        for (a, b) in self.digits.iter_mut().zip(&o.digits) {
            *a += b;
        }
        self.special += o.special;
        self.pending = 1;
    }

    /// Pass the carries on: every digit but the top one in [0, 2^32), the sign in the top one.
    fn carry(&mut self) {
        for j in 0..DIGITS - 1 {
            let c = self.digits[j] >> DIGIT;
            self.digits[j] -= c << DIGIT;
            self.digits[j + 1] += c;
        }
        self.pending = 0;
    }

    /// The sum, rounded to the nearest f64 (ties to even) once; below the smallest normal
    /// f64 (2.2e-308) it may be rounded twice.
    pub fn value(&self) -> f64 {
        if self.special != 0.0 || self.special.is_nan() {
            return self.special;
        }
        let mut t = self.clone();
        t.carry();
        let negative = t.digits[DIGITS - 1] < 0;
        if negative {
            for d in &mut t.digits {
                *d = -*d;
            }
            t.carry();
        }
        let Some(top) = t.digits.iter().rposition(|&d| d != 0) else {
            return 0.0;
        };
        // the top three digits hold at least 65 significant bits, more than the 53 kept;
        // anything nonzero below them only decides a tie, as a sticky bit
        let low = top.saturating_sub(2);
        let mut m: u128 = 0;
        for j in (low..=top).rev() {
            m = (m << DIGIT) | t.digits[j] as u128;
        }
        if t.digits[..low].iter().any(|&d| d != 0) {
            m |= 1;
        }
        let magnitude = scale(m as f64, (DIGIT as usize * low) as i32 - 1074);
        if negative {
            -magnitude
        } else {
            magnitude
        }
    }

    /// The register as bytes (for a merge on another rank).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut t = self.clone();
        t.carry();
        let mut out = Vec::with_capacity(Self::BYTES);
        for d in &t.digits {
            out.extend_from_slice(&d.to_le_bytes());
        }
        out.extend_from_slice(&t.special.to_le_bytes());
        out
    }

    /// A register from [`Self::to_bytes`].
    pub fn from_bytes(b: &[u8]) -> Result<ExactSum, String> {
        if b.len() != Self::BYTES {
            return Err(format!(
                "an exact sum is {} bytes, got {}",
                Self::BYTES,
                b.len()
            ));
        }
        let mut s = ExactSum::default();
        for (d, c) in s.digits.iter_mut().zip(b.chunks_exact(8)) {
            *d = i64::from_le_bytes(c.try_into().expect("8 bytes"));
        }
        s.special = f64::from_le_bytes(b[DIGITS * 8..].try_into().expect("8 bytes"));
        s.pending = 1;
        Ok(s)
    }
}

/// x · 2^n, exact while the result is a normal f64.
fn scale(mut x: f64, mut n: i32) -> f64 {
    let pow2 = |k: i32| f64::from_bits(((k + 1023) as u64) << 52);
    while n > 1000 {
        x *= pow2(1000);
        n -= 1000;
    }
    while n < -1000 {
        x *= pow2(-1000);
        n += 1000;
    }
    x * pow2(n)
}

/// `n` empty registers (one per total of a vector of totals).
pub fn registers(n: usize) -> Vec<ExactSum> {
    vec![ExactSum::default(); n]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sum(xs: &[f64]) -> f64 {
        let mut s = ExactSum::new();
        xs.iter().for_each(|&x| s.add(x));
        s.value()
    }

    /// A few thousand pseudo-random numbers of every sign and a wide range of magnitudes.
    fn numbers(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                let e = ((state >> 3) % 80) as i32 - 40;
                (u - 0.5) * 2f64.powi(e)
            })
            .collect()
    }

    #[test]
    fn one_term_comes_back_unchanged() {
        for x in [
            0.0,
            1.0,
            -1.5,
            0.1,
            -1e-300,
            5e-324,
            -5e-324,
            2.2250738585072014e-308,
            1.7976931348623157e308,
            -1.7976931348623157e308,
            std::f64::consts::PI,
        ] {
            assert_eq!(sum(&[x]).to_bits(), x.to_bits(), "{x}");
        }
        for x in numbers(2000, 7) {
            assert_eq!(sum(&[x]), x);
        }
    }

    #[test]
    fn cancellation_is_exact() {
        assert_eq!(sum(&[1e300, 1.0, -1e300]), 1.0);
        assert_eq!(sum(&[1e16, 1.0, -1e16, 1e-20]), 1.0 + 1e-20);
        // 0.1 + 0.2 − 0.3 of the three f64s is exactly 2^-55 (floating point gives 2^-54)
        assert_eq!(sum(&[0.1, 0.2, -0.3]), 2f64.powi(-55));
    }

    #[test]
    fn the_order_and_the_split_do_not_matter() {
        let xs = numbers(5000, 11);
        let forward = sum(&xs);
        let mut rev = xs.clone();
        rev.reverse();
        assert_eq!(sum(&rev).to_bits(), forward.to_bits());
        // three partial registers merged through their bytes, as three ranks would
        let mut parts = [ExactSum::new(), ExactSum::new(), ExactSum::new()];
        for (i, &x) in xs.iter().enumerate() {
            parts[(i * 7) % 3].add(x);
        }
        let mut total = ExactSum::new();
        for p in &parts {
            total.merge(&ExactSum::from_bytes(&p.to_bytes()).unwrap());
        }
        assert_eq!(total.value().to_bits(), forward.to_bits());
    }

    #[test]
    fn the_result_is_the_correctly_rounded_sum() {
        // integers times 2^-20 below 2^40: their exact sum fits an i128, then one rounding
        let mut state = 3u64;
        let mut exact: i128 = 0;
        let mut s = ExactSum::new();
        for _ in 0..10_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            let k = (state as i64) >> 11; // |k| < 2^53: exactly representable
            exact += k as i128;
            s.add(k as f64 * 2f64.powi(-20));
        }
        assert_eq!(s.value(), exact as f64 * 2f64.powi(-20));
    }

    #[test]
    fn non_finite_terms_win_as_in_ieee() {
        assert_eq!(sum(&[1.0, f64::INFINITY]), f64::INFINITY);
        assert!(sum(&[f64::INFINITY, f64::NEG_INFINITY]).is_nan());
        assert!(sum(&[1.0, f64::NAN]).is_nan());
        assert!(ExactSum::from_bytes(&[0; 3]).is_err());
    }

    #[test]
    fn many_terms_pass_their_carries() {
        let mut s = ExactSum::new();
        s.pending = CARRY_EVERY - 2;
        for _ in 0..10 {
            s.add(f64::MAX);
            s.add(-f64::MAX);
            s.add(0.75);
        }
        assert_eq!(s.value(), 7.5);
    }
}
