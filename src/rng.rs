//! Deterministic number sequences: a small PCG32 generator for Monte Carlo estimates whose error is
//! estimated statistically, and the radical-inverse (Halton) sequence for quasi-Monte Carlo.
//! Both are reproducible bit for bit from their seed or index.

/// PCG-XSH-RR 64/32 (O'Neill 2014).
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Pcg32 { state: 0, inc: (stream << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(6364136223846793005).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// The radical inverse of `i` in base `b`: the `i`-th Halton coordinate.
pub fn radical_inverse(mut i: u64, b: u64) -> f64 {
    let inv = 1.0 / b as f64;
    let mut f = inv;
    let mut r = 0.0;
    while i > 0 {
        r += f * (i % b) as f64;
        i /= b;
        f *= inv;
    }
    r
}

/// Point `i` of the 2D Halton sequence in bases 2 and 3.
pub fn halton2(i: u64) -> (f64, f64) {
    (radical_inverse(i, 2), radical_inverse(i, 3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_first_points() {
        assert_eq!(halton2(1), (0.5, 1.0 / 3.0));
        assert_eq!(halton2(2), (0.25, 2.0 / 3.0));
        assert_eq!(halton2(3), (0.75, 1.0 / 9.0));
    }

    #[test]
    fn pcg_is_uniform_enough() {
        let mut r = Pcg32::new(7, 1);
        let n = 100_000;
        let mean: f64 = (0..n).map(|_| r.next_f64()).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1) is 1/sqrt(12 n) = 9.1e-4; 5 sigma.
        assert!((mean - 0.5).abs() < 5.0 * 9.2e-4, "mean {mean}");
    }
}
