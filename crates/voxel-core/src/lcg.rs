//! A small deterministic random sequence for tests: Knuth's MMIX linear congruential generator.

/// The generator's state: each step multiplies and adds, modulo 2⁶⁴.
pub(crate) struct Lcg(u64);

impl Lcg {
    /// The sequence that starts after `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next state, all 64 bits (the low ones are the least random).
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }

    /// A whole number below `n`, from the top 31 bits.
    pub fn below(&mut self, n: u64) -> u64 {
        (self.next_u64() >> 33) % n
    }

    /// A number in [0, `scale`), from the top 53 bits.
    pub fn unit(&mut self, scale: f64) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * scale
    }
}
