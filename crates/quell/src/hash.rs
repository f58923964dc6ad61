//! Stable hashes, the same on every platform and release (unlike `std::hash`): FNV-1a for
//! fingerprints and identifiers of texts, SplitMix64 for seeds and random streams.

/// FNV-1a over `bytes` with the given offset basis and prime, modulo 2^`bits` (64 or 128): the
/// product is taken in u128 and masked, which is the same as wrapping in a u64 when bits = 64.
fn fnv1a(bytes: impl IntoIterator<Item = u8>, offset: u128, prime: u128, bits: u32) -> u128 {
    let mask = u128::MAX >> (128 - bits);
    bytes.into_iter().fold(offset, |h, b| ((h ^ u128::from(b)).wrapping_mul(prime)) & mask)
}

/// FNV-1a, 64 bits: a study's fingerprint, the generated C's layout id.
pub(crate) fn fnv1a_64(bytes: impl IntoIterator<Item = u8>) -> u64 {
    fnv1a(bytes, 0xcbf2_9ce4_8422_2325, 0x0100_0000_01b3, 64) as u64
}

/// FNV-1a, 128 bits: an FMU's GUID.
pub(crate) fn fnv1a_128(bytes: impl IntoIterator<Item = u8>) -> u128 {
    fnv1a(bytes, 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d, 0x0000_0000_0100_0000_0000_0000_0000_013b, 128)
}

/// SplitMix64's increment (Steele, Lea, Flood 2014), ⌊2^64/φ⌋: the state's step.
pub(crate) const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's finalizer: a bijection of u64 that scrambles every bit (the output of the state z).
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published test vectors (Eastlake, Hansen, Fowler, Vo, Noll, "The FNV Non-Cryptographic Hash
    /// Algorithm", IETF draft-eastlake-fnv, and the FNV reference suite `test_fnv.c`):
    /// FNV-1a 64 of "", "a", "foobar"; FNV-1a 128 of "" (its offset basis), "a", "foobar".
    #[test]
    fn fnv1a_matches_the_published_vectors() {
        assert_eq!(fnv1a_64(*b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a_64(*b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a_64(*b"foobar"), 0x8594_4171_f739_67e8);
        assert_eq!(fnv1a_128(*b""), 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d);
        assert_eq!(fnv1a_128(*b"a"), 0xd228_cb69_6f1a_8caf_7891_2b70_4e4a_8964);
        assert_eq!(fnv1a_128(*b"foobar"), 0x343e_1662_793c_64bf_6f0d_3597_ba44_6f18);
    }

    /// SplitMix64 seeded with 0 (Vigna's `splitmix64.c`): first outputs e220a8397b1dcdaf,
    /// 6e789e6aa1b965f4, 06c45d188009454f.
    #[test]
    fn splitmix64_matches_the_reference_stream() {
        let mut state = 0u64;
        let mut next = || {
            state = state.wrapping_add(GOLDEN_GAMMA);
            mix64(state)
        };
        assert_eq!([next(), next(), next()], [0xe220_a839_7b1d_cdaf, 0x6e78_9e6a_a1b9_65f4, 0x06c4_5d18_8009_454f]);
    }
}
