//! A fast hasher for the caches' keys, which are words this program made (bit patterns of
//! f64s, counts, addresses), never input an attacker chooses: SipHash (`DefaultHasher`), built
//! to resist chosen keys, spent about ten instructions per byte on them.
//!
//! [`WordHasher`] folds each 64-bit word `x` into the state `h` as `h = (rotl(h, 5) ^ x) ·
//! 0x517cc1b727220a95` (the multiply-rotate scheme of rustc's `FxHasher`), bytes as
//! little-endian words (the last one zero-padded), and finishes with `rotl(h, 26)`: the
//! multiply carries each word into the high bits, and the hash table reads its bucket from the
//! low ones. Equal keys hash equally, which is all a map needs for its answers; a poor spread
//! would cost time only. The hash is the same on every run (no random seed), so a map's
//! iteration order is too, although no caller depends on it.

use std::hash::{BuildHasherDefault, Hasher};

/// The hasher of the module's documentation.
#[derive(Debug, Clone, Copy, Default)]
pub struct WordHasher(u64);

/// Its multiplier (rustc's `FxHasher`'s 64-bit seed).
const K: u64 = 0x517c_c1b7_2722_0a95;

impl Hasher for WordHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.write_u64(u64::from_le_bytes(w.try_into().expect("eight bytes")));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut word = [0u8; 8];
            word[..rest.len()].copy_from_slice(rest);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    #[inline]
    fn write_u8(&mut self, x: u8) {
        self.write_u64(u64::from(x));
    }

    #[inline]
    fn write_u32(&mut self, x: u32) {
        self.write_u64(u64::from(x));
    }

    #[inline]
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(K);
    }

    #[inline]
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.0.rotate_left(26)
    }
}

/// A `HashMap` hashed by [`WordHasher`].
pub type WordMap<K, V> = std::collections::HashMap<K, V, BuildHasherDefault<WordHasher>>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::{BuildHasher, Hash};

    fn hash_of<T: Hash + ?Sized>(x: &T) -> u64 {
        BuildHasherDefault::<WordHasher>::default().hash_one(x)
    }

    /// The words are folded as the documentation says: a key of words hashes to the fold
    /// computed by hand (its length first, as `Vec`'s `Hash` writes it, then each word).
    #[test]
    fn a_key_of_words_hashes_to_the_stated_fold() {
        let key: Vec<u64> = vec![3, 0x4010_0000_0000_0000, u64::MAX, 0];
        let mut h = 0u64;
        for x in std::iter::once(key.len() as u64).chain(key.iter().copied()) {
            h = (h.rotate_left(5) ^ x).wrapping_mul(K);
        }
        assert_eq!(hash_of(&key), h.rotate_left(26));
        // Bytes: whole words little-endian, the last one zero-padded.
        let mut a = WordHasher::default();
        a.write(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]);
        let mut b = WordHasher::default();
        b.write_u64(u64::from_le_bytes([1, 2, 3, 4, 5, 6, 7, 8]));
        b.write_u64(u64::from_le_bytes([9, 10, 0, 0, 0, 0, 0, 0]));
        assert_eq!(a.finish(), b.finish());
    }

    /// A map keyed by the caches' kind of keys (f64 bits of nearby values, small counts) finds
    /// every key it holds and none it does not, against a sorted list of the same keys; and
    /// the keys spread: no bucket index (the low bits) takes more than a few of them.
    #[test]
    fn a_word_map_answers_as_a_list_does_and_spreads_the_keys() {
        let keys: Vec<Vec<u64>> = (0..4000u64)
            .map(|i| {
                vec![
                    i % 7,
                    (1.0 + i as f64 * 1e-3).to_bits(),
                    (0.25 * (i / 7) as f64).to_bits(),
                ]
            })
            .collect();
        let mut map: WordMap<Vec<u64>, usize> = WordMap::default();
        for (i, k) in keys.iter().enumerate().filter(|(i, _)| i % 3 != 0) {
            map.insert(k.clone(), i);
        }
        let mut listed: Vec<(Vec<u64>, usize)> = keys
            .iter()
            .cloned()
            .enumerate()
            .filter(|(i, _)| i % 3 != 0)
            .map(|(i, k)| (k, i))
            .collect();
        listed.sort();
        for k in &keys {
            let by_list = listed.binary_search_by(|(x, _)| x.cmp(k)).ok().map(|at| listed[at].1);
            assert_eq!(map.get(k).copied(), by_list, "{k:?}");
        }
        // 4000 keys into 4096 buckets by the low 12 bits: a uniform spread puts at most about
        // 7 in one; a bad fold would pile them up.
        let mut buckets = vec![0u32; 4096];
        for k in &keys {
            buckets[(hash_of(k) & 4095) as usize] += 1;
        }
        let most = *buckets.iter().max().unwrap();
        assert!(most <= 9, "{most} keys share a bucket");
    }
}
