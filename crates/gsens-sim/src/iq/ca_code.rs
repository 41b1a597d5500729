//! GPS L1 C/A codes (IS-GPS-200, §3.3.2.3 and Table 3-Ia).
//!
//! Each code is the modulo-2 sum of two 10-stage maximal-length sequences:
//! G1 (feedback taps 3 and 10, polynomial 1 + x³ + x¹⁰) and G2 (taps 2, 3, 6,
//! 8, 9, 10, polynomial 1 + x² + x³ + x⁶ + x⁸ + x⁹ + x¹⁰), both registers
//! starting all ones. The PRN-specific delay of G2 is obtained by adding two
//! of its stages (the "G2 phase selection" taps of Table 3-Ia). The code is
//! 1023 chips long and repeats every millisecond at 1.023 Mchip/s.

/// Chips per code period.
pub const CA_CODE_LENGTH: usize = 1023;
/// Chipping rate [chip/s].
pub const CA_CHIP_RATE_HZ: f64 = 1.023e6;
/// Highest PRN with a C/A code in [`G2_TAPS`].
pub const MAX_CA_PRN: u32 = 32;

/// G2 phase-selection taps (1-based register stages) for PRN 1…32,
/// IS-GPS-200 Table 3-Ia.
pub const G2_TAPS: [(u8, u8); 32] = [
    (2, 6),
    (3, 7),
    (4, 8),
    (5, 9),
    (1, 9),
    (2, 10),
    (1, 8),
    (2, 9),
    (3, 10),
    (2, 3),
    (3, 4),
    (5, 6),
    (6, 7),
    (7, 8),
    (8, 9),
    (9, 10),
    (1, 4),
    (2, 5),
    (3, 6),
    (4, 7),
    (5, 8),
    (6, 9),
    (1, 3),
    (4, 6),
    (5, 7),
    (6, 8),
    (7, 9),
    (8, 10),
    (1, 6),
    (2, 7),
    (3, 8),
    (4, 9),
];

/// The C/A code of `prn` (1…32) as bits 0/1, chip 0 first; `None` for other PRNs.
pub fn ca_code_bits(prn: u32) -> Option<[u8; CA_CODE_LENGTH]> {
    if !(1..=MAX_CA_PRN).contains(&prn) {
        return None;
    }
    let (t1, t2) = G2_TAPS[(prn - 1) as usize];
    // Registers as arrays, index 0 = stage 1.
    let mut g1 = [1u8; 10];
    let mut g2 = [1u8; 10];
    let mut out = [0u8; CA_CODE_LENGTH];
    for chip in out.iter_mut() {
        let g1_out = g1[9];
        let g2_out = g2[usize::from(t1) - 1] ^ g2[usize::from(t2) - 1];
        *chip = g1_out ^ g2_out;
        let f1 = g1[2] ^ g1[9];
        let f2 = g2[1] ^ g2[2] ^ g2[5] ^ g2[7] ^ g2[8] ^ g2[9];
        g1.copy_within(0..9, 1);
        g2.copy_within(0..9, 1);
        g1[0] = f1;
        g2[0] = f2;
    }
    Some(out)
}

/// The C/A code of `prn` as ±1 (bit 0 → +1, bit 1 → −1: the usual BPSK
/// mapping); `None` for PRNs without a code.
pub fn ca_code_bipolar(prn: u32) -> Option<[i8; CA_CODE_LENGTH]> {
    ca_code_bits(prn).map(|b| b.map(|x| 1 - 2 * x as i8))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 10 chips in octal, IS-GPS-200 Table 3-Ia, PRN 1…32.
    const FIRST_10_OCTAL: [u16; 32] = [
        0o1440, 0o1620, 0o1710, 0o1744, 0o1133, 0o1455, 0o1131, 0o1454, 0o1626, 0o1504, 0o1642, 0o1750, 0o1764, 0o1772,
        0o1775, 0o1776, 0o1156, 0o1467, 0o1633, 0o1715, 0o1746, 0o1763, 0o1063, 0o1706, 0o1743, 0o1761, 0o1770, 0o1774,
        0o1127, 0o1453, 0o1625, 0o1712,
    ];

    #[test]
    fn first_ten_chips_match_the_icd() {
        for prn in 1..=32u32 {
            let c = ca_code_bits(prn).unwrap();
            let v = c[..10].iter().fold(0u16, |acc, &b| (acc << 1) | u16::from(b));
            assert_eq!(v, FIRST_10_OCTAL[(prn - 1) as usize], "PRN {prn}: {v:o}");
        }
        assert!(ca_code_bits(0).is_none() && ca_code_bits(33).is_none());
    }

    #[test]
    fn balanced_and_nearly_orthogonal() {
        // Gold codes: 512 ones and 511 zeros; cross-correlation values in {−65, −1, 63}.
        let codes: Vec<[i8; CA_CODE_LENGTH]> = (1..=32).map(|p| ca_code_bipolar(p).unwrap()).collect();
        for c in &codes {
            assert_eq!(c.iter().map(|&x| i32::from(x)).sum::<i32>(), -1);
        }
        for (a, b) in [(0usize, 1usize), (4, 17), (30, 31)] {
            for lag in [0usize, 1, 100, 511] {
                let r: i32 = (0..CA_CODE_LENGTH)
                    .map(|i| i32::from(codes[a][i]) * i32::from(codes[b][(i + lag) % CA_CODE_LENGTH]))
                    .sum();
                assert!([-65, -1, 63].contains(&r), "PRN {} × {} lag {lag}: {r}", a + 1, b + 1);
            }
        }
    }
}
