//! The unit tests' random numbers: a small deterministic generator (xorshift), so that the tests
//! need no dependency and every run draws the same cases.

/// The xorshift sequence from `seed` (made odd: the state must not be zero).
pub(crate) fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}
