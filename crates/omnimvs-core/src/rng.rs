//! The workspace's one seeded generator, SplitMix64 (Steele, Lea and Flood
//! 2014): 64 bits of state, full period, fast, and written here rather than
//! taken from a crate so that a seed gives the same scenes and the same
//! training shuffles with every future dependency version. `omnimvs-synth`
//! adds its scene distributions on top (`omnimvs_synth::rng::Rng`), the
//! trainer its epoch streams.

/// The golden-ratio increment of SplitMix64's state.
pub const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (a 64-bit finaliser): also a good hash for
/// deriving seeds.
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// SplitMix64. Equal states give equal streams on every platform.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator whose state is `state` (no mixing of the seed).
    pub fn new(state: u64) -> Self {
        Self { state }
    }

    /// The stream of pass `epoch` of a run seeded with `seed` (the trainer's
    /// shuffles and draws): every epoch has its own stream, so a run resumed
    /// at an epoch boundary makes the same choices as an uninterrupted one.
    pub fn for_epoch(seed: u64, epoch: usize) -> Self {
        let mut g = Self::new(seed ^ 0x6f6d_6e69_6d76_7321);
        for _ in 0..=epoch % 7 {
            g.next_u64();
        }
        Self::new(g.next_u64() ^ (epoch as u64).wrapping_mul(GAMMA))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GAMMA);
        mix64(self.state)
    }

    /// Uniform in `[0, 1)`, with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `0..n` (`n > 0`), by the high half of a 128-bit product.
    pub fn below(&mut self, n: usize) -> usize {
        debug_assert!(n > 0);
        ((u128::from(self.next_u64()) * n as u128) >> 64) as usize
    }

    /// Fisher-Yates shuffle.
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            let j = self.below(i + 1);
            items.swap(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The published SplitMix64 reference stream for seed 1234567
    /// (`splitmix64.c`, Vigna): the generator is the standard one.
    #[test]
    fn matches_the_reference_stream() {
        let mut g = SplitMix64::new(1_234_567);
        let want = [
            6_457_827_717_110_365_317u64,
            3_203_168_211_198_807_973,
            9_817_491_932_198_370_423,
            4_593_380_528_125_082_431,
            16_408_922_859_458_223_821,
        ];
        for w in want {
            assert_eq!(g.next_u64(), w);
        }
    }

    #[test]
    fn epochs_have_distinct_reproducible_streams() {
        let a: Vec<u64> = (0..4)
            .map(|_| SplitMix64::for_epoch(7, 3).next_u64())
            .collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            SplitMix64::for_epoch(7, 3).next_u64(),
            SplitMix64::for_epoch(7, 4).next_u64()
        );
        let mut g = SplitMix64::new(1);
        let mut v: Vec<usize> = (0..50).collect();
        g.shuffle(&mut v);
        let mut sorted = v.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..50).collect::<Vec<_>>());
        assert_ne!(v, sorted);
        assert!((0..1000).all(|_| g.below(3) < 3 && (0.0..1.0).contains(&g.next_f64())));
    }

    /// Golden values of the trainer's epoch streams, printed by the trainer's own
    /// generator (`omnimvs-net/src/train/rng.rs` at commit 13900ed) before it moved
    /// here: resumed training runs depend on them.
    #[test]
    fn epoch_streams_are_unchanged() {
        let mut g = SplitMix64::for_epoch(9, 2);
        let got: Vec<u64> = (0..3).map(|_| g.next_u64()).collect();
        assert_eq!(got, EPOCH_9_2);
        let mut order: Vec<usize> = (0..10).collect();
        SplitMix64::for_epoch(0, 0).shuffle(&mut order);
        assert_eq!(order, SHUFFLE_0_0);
    }

    const EPOCH_9_2: [u64; 3] = [
        10_316_485_439_416_516_526,
        4_431_002_754_623_737_679,
        13_302_248_441_638_162_757,
    ];
    const SHUFFLE_0_0: [usize; 10] = [8, 1, 6, 3, 0, 4, 9, 2, 5, 7];
}
