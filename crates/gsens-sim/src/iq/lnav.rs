//! GPS LNAV navigation-message subframes for the L1 C/A signal
//! (IS-GPS-200, §20.3.2 and §20.3.5): 300-bit subframes of ten 30-bit words
//! at 50 bit/s, a subframe every 6 s.
//!
//! What a receiver needs to synchronize and decode the frame is real here:
//!
//! - word 1 (TLM): the preamble `10001011`, a zero TLM message, integrity and
//!   reserved bits 0;
//! - word 2 (HOW): the truncated time-of-week count of the *next* subframe's
//!   leading edge (17 bits, 6 s units), alert and anti-spoof flags 0, the
//!   subframe ID 1…5 (subframe 1 starts every 30 s of GPS time), and bits 23–24
//!   solved so that the word's last two parity bits are 0;
//! - subframe 1, word 3: the week number modulo 1024 (the rest of the clock
//!   data zero);
//! - every other data bit 0, except bits 23–24 of word 10, again solved so that
//!   D29 = D30 = 0 (so every TLM word goes out uninverted);
//! - the parity of every word (Table 20-XIV), with the complementing of bits
//!   1–24 by D30* of the previous word.
//!
//! The ephemeris and almanac fields are zero: a receiver synchronizes,
//! checks parity and reads the time, but computes no position from it.

/// Bits per subframe.
pub const SUBFRAME_BITS: usize = 300;
/// Seconds per subframe.
pub const SUBFRAME_S: f64 = 6.0;
/// Subframes per GPS week.
pub const SUBFRAMES_PER_WEEK: i64 = 100_800;
/// The TLM preamble, bits 1–8 of word 1.
pub const PREAMBLE: u32 = 0b1000_1011;

/// Parity masks of Table 20-XIV on a 32-bit word laid out as
/// `[D29*, D30*, d1 … d24, 6 zero bits]` (bit 31 = D29*, bit 30 = D30*, bit 29 = d1):
/// D25 … D30 are the modulo-2 sums of the bits each mask selects.
const PARITY_MASKS: [u32; 6] = [0xBB1F_3480, 0x5D8F_9A40, 0xAEC7_CD00, 0x5763_E680, 0x6BB1_F340, 0x8B7A_89C0];

/// Encodes 24 source data bits `data24` (d1 = bit 23) after a word whose last
/// two transmitted bits were `d29_star`, `d30_star`: returns the 30
/// transmitted bits (D1 = bit 29), i.e. D1…D24 = d ⊕ D30* and the parity D25…D30.
pub fn encode_word(data24: u32, d29_star: u32, d30_star: u32) -> u32 {
    let data24 = data24 & 0x00FF_FFFF;
    let x = (d29_star & 1) << 31 | (d30_star & 1) << 30 | data24 << 6;
    let mut parity = 0u32;
    for m in PARITY_MASKS {
        parity = (parity << 1) | ((x & m).count_ones() & 1);
    }
    let sent = if d30_star & 1 == 1 { !data24 & 0x00FF_FFFF } else { data24 };
    sent << 6 | parity
}

/// Whether a received 30-bit word `word` (D1 = bit 29) passes the parity check
/// after a word ending in `d29_star`, `d30_star`.
pub fn parity_ok(word: u32, d29_star: u32, d30_star: u32) -> bool {
    let sent = (word >> 6) & 0x00FF_FFFF;
    let data = if d30_star & 1 == 1 { !sent & 0x00FF_FFFF } else { sent };
    encode_word(data, d29_star, d30_star) == word & 0x3FFF_FFFF
}

/// Encodes a word whose data bits 23–24 are free: picks them so that the
/// transmitted D29 = D30 = 0.
fn encode_word_solved(data22: u32, d29_star: u32, d30_star: u32) -> u32 {
    let base = data22 & 0x00FF_FFFC;
    (0..4)
        .map(|t| encode_word(base | t, d29_star, d30_star))
        .find(|w| w & 0b11 == 0)
        .expect("two free bits always solve D29 = D30 = 0")
}

/// The 300 bits (0/1, first transmitted first) of the subframe that starts at
/// GPS time `subframe_index`·6 s (`subframe_index` counted from the GPS epoch,
/// 1980-01-06 00:00:00).
pub fn subframe_bits(subframe_index: i64) -> [u8; SUBFRAME_BITS] {
    let week = subframe_index.div_euclid(SUBFRAMES_PER_WEEK);
    let tow_count = subframe_index.rem_euclid(SUBFRAMES_PER_WEEK);
    let next_tow_count = (tow_count + 1) % SUBFRAMES_PER_WEEK;
    let subframe_id = (tow_count % 5 + 1) as u32;
    let mut words = [0u32; 10];
    // The previous subframe's word 10 ends in D29 = D30 = 0.
    let (mut d29, mut d30) = (0u32, 0u32);
    for (i, w) in words.iter_mut().enumerate() {
        let data = match i {
            0 => PREAMBLE << 16,
            1 => (next_tow_count as u32) << 7 | subframe_id << 2,
            2 if subframe_id == 1 => ((week.rem_euclid(1024)) as u32) << 14,
            _ => 0,
        };
        *w = if i == 1 || i == 9 { encode_word_solved(data, d29, d30) } else { encode_word(data, d29, d30) };
        d29 = (*w >> 1) & 1;
        d30 = *w & 1;
    }
    let mut bits = [0u8; SUBFRAME_BITS];
    for (i, w) in words.iter().enumerate() {
        for b in 0..30 {
            bits[i * 30 + b] = ((w >> (29 - b)) & 1) as u8;
        }
    }
    bits
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The masks written out as the index lists of Table 20-XIV.
    #[test]
    fn masks_match_the_parity_equations() {
        let lists: [(u32, &[u32]); 6] = [
            (29, &[1, 2, 3, 5, 6, 10, 11, 12, 13, 14, 17, 18, 20, 23]),
            (30, &[2, 3, 4, 6, 7, 11, 12, 13, 14, 15, 18, 19, 21, 24]),
            (29, &[1, 3, 4, 5, 7, 8, 12, 13, 14, 15, 16, 19, 20, 22]),
            (30, &[2, 4, 5, 6, 8, 9, 13, 14, 15, 16, 17, 20, 21, 23]),
            (30, &[1, 3, 5, 6, 7, 9, 10, 14, 15, 16, 17, 18, 21, 22, 24]),
            (29, &[3, 5, 6, 8, 9, 10, 11, 13, 15, 19, 22, 23, 24]),
        ];
        for (mask, (star, ds)) in PARITY_MASKS.iter().zip(lists) {
            let mut m = if star == 29 { 1u32 << 31 } else { 1u32 << 30 };
            for d in ds {
                m |= 1 << (30 - d);
            }
            assert_eq!(*mask, m, "{mask:08X}");
        }
    }

    fn word(bits: &[u8]) -> u32 {
        bits.iter().fold(0, |acc, &b| acc << 1 | u32::from(b))
    }

    #[test]
    fn subframes_parse_back() {
        // 2024-02-08T12:00:00 GPS ≈ week 2300, TOW 388 800 s: subframe index.
        let start = 2300 * SUBFRAMES_PER_WEEK + 388_800 / 6;
        let (mut d29, mut d30) = (0, 0);
        for k in 0..12 {
            let bits = subframe_bits(start + k);
            for w in 0..10 {
                let x = word(&bits[w * 30..w * 30 + 30]);
                assert!(parity_ok(x, d29, d30), "subframe {k} word {w}");
                d29 = (x >> 1) & 1;
                d30 = x & 1;
            }
            assert_eq!(word(&bits[..8]), PREAMBLE, "preamble uninverted");
            let how = word(&bits[30..60]) >> 6;
            let tow_next = how >> 7;
            let id = (how >> 2) & 7;
            assert_eq!(i64::from(tow_next), (388_800 / 6 + k + 1) % SUBFRAMES_PER_WEEK);
            assert_eq!(i64::from(id), (388_800 / 6 + k) % 5 + 1);
            assert_eq!(word(&bits[58..60]), 0, "HOW ends in 00");
            assert_eq!(word(&bits[298..300]), 0, "word 10 ends in 00");
            if id == 1 {
                // Word 3 of subframe 1: the week number modulo 1024 (HOW ends in D30 = 0: uninverted).
                assert_eq!(word(&bits[60..70]), 2300 % 1024);
            }
        }
    }

    #[test]
    fn parity_detects_single_bit_errors() {
        let w = encode_word(0x00AB_CDEF, 1, 0);
        assert!(parity_ok(w, 1, 0));
        for b in 0..30 {
            assert!(!parity_ok(w ^ (1 << b), 1, 0), "bit {b}");
        }
    }
}
