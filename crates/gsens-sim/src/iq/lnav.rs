//! GPS LNAV navigation-message subframes for the L1 C/A signal
//! (IS-GPS-200, §20.3.2 and §20.3.5): 300-bit subframes of ten 30-bit words
//! at 50 bit/s, a subframe every 6 s.
//!
//! - word 1 (TLM): the preamble `10001011`, a zero TLM message, integrity and
//!   reserved bits 0;
//! - word 2 (HOW): the truncated time-of-week count of the *next* subframe's
//!   leading edge (17 bits, 6 s units), alert and anti-spoof flags 0, the
//!   subframe ID 1…5 (subframe 1 starts every 30 s of GPS time), and bits 23–24
//!   solved so that the word's last two parity bits are 0;
//! - subframes 1–3, words 3–10: the satellite's [`Ephemeris`] (clock and
//!   orbit, §20.3.3.3 and §20.3.3.4, Figure 20-1), or zeros without one;
//! - subframes 4 and 5: every data bit 0 (data ID and SV ID 0: pages a
//!   receiver skips);
//! - bits 23–24 of word 10 solved so that D29 = D30 = 0 (so every TLM word
//!   goes out uninverted);
//! - the parity of every word (Table 20-XIV), with the complementing of bits
//!   1–24 by D30* of the previous word.

use crate::satellites::{AlmanacEntry, EARTH_ROTATION_RADPS, SECONDS_PER_WEEK};
use std::f64::consts::PI;

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
/// 1980-01-06 00:00:00), with `ephemeris` in subframes 1–3 (zeros but the
/// week number without one).
pub fn subframe_bits(subframe_index: i64, ephemeris: Option<&Ephemeris>) -> [u8; SUBFRAME_BITS] {
    let week = subframe_index.div_euclid(SUBFRAMES_PER_WEEK);
    let tow_count = subframe_index.rem_euclid(SUBFRAMES_PER_WEEK);
    let next_tow_count = (tow_count + 1) % SUBFRAMES_PER_WEEK;
    let subframe_id = (tow_count % 5 + 1) as u32;
    let mut words = [0u32; 10];
    // The previous subframe's word 10 ends in D29 = D30 = 0.
    let (mut d29, mut d30) = (0u32, 0u32);
    for (i, w) in words.iter_mut().enumerate() {
        let data = match (i, ephemeris) {
            (0, _) => PREAMBLE << 16,
            (1, _) => (next_tow_count as u32) << 7 | subframe_id << 2,
            (_, Some(e)) if subframe_id <= 3 => e.subframe_words(subframe_id)[i - 2],
            (2, None) if subframe_id == 1 => ((week.rem_euclid(1024)) as u32) << 14,
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

/// 2ⁿ as f64 for the scale factors of IS-GPS-200 Table 20-III.
fn pow2(n: i32) -> f64 {
    2f64.powi(n)
}

/// A broadcast ephemeris of one satellite as subframes 1–3 carry it, each
/// field the integer count of its scale factor (IS-GPS-200 Table 20-III):
/// the clock and orbit of a satellite whose orbit is Keplerian. Sent as zero:
/// the satellite clock (a_f0, a_f1, a_f2, T_GD: the satellite's clock keeps
/// GPS time but for its relativistic term), Δn, IDOT and the six harmonic
/// corrections (C_rs … C_ic); URA index 0, health 0, the fit interval flag 0,
/// AODO 0. IODC = IODE (its two most significant bits 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ephemeris {
    /// PRN number.
    pub prn: u32,
    /// Full GPS week of t_oe.
    pub week: u32,
    /// t_oe = t_oc [units of 16 s of week].
    pub toe_16s: u16,
    /// Issue of data (IODE = IODC).
    pub iode: u8,
    /// Mean anomaly at t_oe M₀ [2⁻³¹ semicircles].
    pub m0: i32,
    /// Eccentricity e [2⁻³³].
    pub e: u32,
    /// Square root of the semi-major axis √A [2⁻¹⁹ m^½].
    pub sqrt_a: u32,
    /// Longitude of the ascending node at the weekly epoch Ω₀ [2⁻³¹ semicircles].
    pub omega0: i32,
    /// Inclination at t_oe i₀ [2⁻³¹ semicircles].
    pub i0: i32,
    /// Argument of perigee ω [2⁻³¹ semicircles].
    pub omega: i32,
    /// Rate of right ascension Ω̇ [2⁻⁴³ semicircles/s], a 24-bit field.
    pub omega_dot: i32,
}

/// Why an orbit has no broadcast ephemeris: a field beyond its bits.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EphemerisError {
    /// The field does not fit its bits in IS-GPS-200 Table 20-III.
    #[error("PRN {prn}: {field} = {value} does not fit the broadcast ephemeris's field")]
    OutOfRange {
        /// The satellite.
        prn: u32,
        /// The field (`e`, `sqrt_a`, `omega_dot`).
        field: &'static str,
        /// Its value in the almanac's units (rad, m^½, rad/s).
        value: f64,
    },
}

/// An angle in radians as a count of 2^`lsb` semicircles, modulo 2³²
/// (two's complement wraps whole turns away).
fn semicircles(rad: f64, lsb: i32) -> i32 {
    (rad.rem_euclid(2.0 * PI) / PI / pow2(lsb)).round() as i64 as u32 as i32
}

impl Ephemeris {
    /// The ephemeris, with reference time `toe_gps_s` (GPS seconds since the GPS
    /// epoch, rounded to 16 s), of the Keplerian orbit `orbit` of the
    /// almanac user algorithm ([`AlmanacEntry::state_ecef`]): the same
    /// elements moved from t_oa to t_oe,
    ///
    /// ```text
    /// M₀(t_oe) = M₀ + n·(t_oe − t_oa),   n = √(μ/A³)
    /// Ω₀(t_oe) = Ω₀ + (Ω̇ − Ω̇ₑ)·(t_oe − t_oa) + Ω̇ₑ·(toe_s − toa_s)
    /// ```
    ///
    /// (times continuous GPS seconds but toe_s, toa_s seconds of their weeks:
    /// both expressions give Ω = Ω₀ + (Ω̇ − Ω̇ₑ)·t_k − Ω̇ₑ·t_ref of
    /// IS-GPS-200 Table 20-IV), then quantized to the broadcast fields.
    /// IODE: t_oe's count of 16 s modulo 256.
    pub fn of_orbit(orbit: &AlmanacEntry, toe_gps_s: f64) -> Result<Ephemeris, EphemerisError> {
        let toe_count = (toe_gps_s / 16.0).round() as i64;
        let toe_gps_s = toe_count as f64 * 16.0;
        let week = (toe_gps_s / SECONDS_PER_WEEK).floor();
        let toe_s = toe_gps_s - week * SECONDS_PER_WEEK;
        let dt = toe_gps_s - orbit.toa_gps_s();
        let m0 = orbit.mean_anomaly_rad + orbit.mean_motion_radps() * dt;
        let omega0 = orbit.raan0_rad
            + (orbit.raan_rate_radps - EARTH_ROTATION_RADPS) * dt
            + EARTH_ROTATION_RADPS * (toe_s - orbit.toa_s);
        let out_of_range = |field, value| EphemerisError::OutOfRange { prn: orbit.prn, field, value };
        let unsigned = |x: f64, lsb: i32, bits: u32, field| {
            let n = (x / pow2(lsb)).round();
            if (0.0..pow2(bits as i32)).contains(&n) { Ok(n as u32) } else { Err(out_of_range(field, x)) }
        };
        let e = unsigned(orbit.eccentricity, -33, 32, "e")?;
        let sqrt_a = unsigned(orbit.sqrt_a_sqrtm, -19, 32, "sqrt_a")?;
        let omega_dot = (orbit.raan_rate_radps / PI / pow2(-43)).round();
        if omega_dot.abs() >= pow2(23) {
            return Err(out_of_range("omega_dot", orbit.raan_rate_radps));
        }
        Ok(Ephemeris {
            prn: orbit.prn,
            week: week as u32,
            toe_16s: (toe_s / 16.0).round() as u16,
            iode: toe_count.rem_euclid(256) as u8,
            m0: semicircles(m0, -31),
            e,
            sqrt_a,
            omega0: semicircles(omega0, -31),
            i0: semicircles(orbit.inclination_rad, -31),
            omega: semicircles(orbit.arg_perigee_rad, -31),
            omega_dot: omega_dot as i32,
        })
    }

    /// t_oe in GPS seconds since the GPS epoch.
    pub fn toe_gps_s(&self) -> f64 {
        f64::from(self.week) * SECONDS_PER_WEEK + f64::from(self.toe_16s) * 16.0
    }

    /// The broadcast orbit as almanac elements at t_oa = t_oe: with Δn,
    /// IDOT and the harmonic corrections zero the ephemeris user algorithm
    /// (IS-GPS-200 Table 20-IV) is the almanac one, so
    /// [`AlmanacEntry::state_ecef`] of this entry is the satellite position
    /// a receiver computes from the message.
    pub fn orbit(&self) -> AlmanacEntry {
        let sc = |n: i32, lsb: i32| f64::from(n) * pow2(lsb) * PI;
        AlmanacEntry {
            prn: self.prn,
            health: 0,
            eccentricity: f64::from(self.e) * pow2(-33),
            toa_s: f64::from(self.toe_16s) * 16.0,
            inclination_rad: sc(self.i0, -31),
            raan_rate_radps: sc(self.omega_dot, -43),
            sqrt_a_sqrtm: f64::from(self.sqrt_a) * pow2(-19),
            raan0_rad: sc(self.omega0, -31),
            arg_perigee_rad: sc(self.omega, -31),
            mean_anomaly_rad: sc(self.m0, -31),
            af0_s: 0.0,
            af1_sps: 0.0,
            week: self.week,
        }
    }

    /// The 24 data bits (d1 = bit 23) of words 3–10 of subframe `id` (1, 2
    /// or 3; Figure 20-1), word 10's last two bits 0 (solved later for
    /// D29 = D30 = 0).
    pub fn subframe_words(&self, id: u32) -> [u32; 8] {
        let iode = u32::from(self.iode);
        let toe = u32::from(self.toe_16s);
        let hi8 = |x: u32| x >> 24;
        let lo24 = |x: u32| x & 0x00FF_FFFF;
        let m0 = self.m0 as u32;
        let (om0, i0, om) = (self.omega0 as u32, self.i0 as u32, self.omega as u32);
        let (sqa, e) = (self.sqrt_a, self.e);
        match id {
            // WN (10) | code on L2 (2) = 0 | URA (4) = 0 | health (6) = 0 | IODC MSBs (2) = 0;
            // L2 P flag and reserved; reserved ×2; reserved (16) | T_GD (8) = 0;
            // IODC LSBs (8) | t_oc (16); a_f2 (8) = 0 | a_f1 (16) = 0; a_f0 (22) = 0 | t (2).
            1 => [(self.week % 1024) << 14 | (iode >> 8), 0, 0, 0, 0, (iode & 0xFF) << 16 | toe, 0, 0],
            // IODE | C_rs = 0; Δn = 0 | M₀ MSBs; M₀ LSBs; C_uc = 0 | e MSBs; e LSBs;
            // C_us = 0 | √A MSBs; √A LSBs; t_oe | fit flag = 0 | AODO = 0 | t (2).
            2 => [iode << 16, hi8(m0), lo24(m0), hi8(e), lo24(e), hi8(sqa), lo24(sqa), toe << 8],
            // C_ic = 0 | Ω₀ MSBs; Ω₀ LSBs; C_is = 0 | i₀ MSBs; i₀ LSBs; C_rc = 0 | ω MSBs;
            // ω LSBs; Ω̇ (24); IODE | IDOT (14) = 0 | t (2).
            3 => [
                hi8(om0),
                lo24(om0),
                hi8(i0),
                lo24(i0),
                hi8(om),
                lo24(om),
                self.omega_dot as u32 & 0x00FF_FFFF,
                iode << 16,
            ],
            _ => [0; 8],
        }
    }
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

    /// The source data bits of a subframe as a receiver recovers them: each
    /// word's parity checked, bits 1–24 complemented after a word ending in
    /// D30* = 1; indexed 1…300 as in IS-GPS-200 Figure 20-1 (index 0 unused).
    fn received_subframe(bits: &[u8], (d29, d30): &mut (u32, u32)) -> Vec<u8> {
        let mut out = vec![0u8; 301];
        for w in 0..10 {
            let x = word(&bits[w * 30..w * 30 + 30]);
            assert!(parity_ok(x, *d29, *d30), "word {}", w + 1);
            for b in 0..30 {
                let raw = bits[w * 30 + b];
                out[w * 30 + b + 1] = if b < 24 && *d30 == 1 { raw ^ 1 } else { raw };
            }
            *d29 = (x >> 1) & 1;
            *d30 = x & 1;
        }
        out
    }

    /// A field of a received subframe from its pieces (first bit, length),
    /// most significant first, as unsigned or two's complement.
    fn field(sf: &[u8], pieces: &[(usize, usize)]) -> u64 {
        pieces.iter().flat_map(|&(start, len)| start..start + len).fold(0, |acc, i| acc << 1 | u64::from(sf[i]))
    }
    fn signed(sf: &[u8], pieces: &[(usize, usize)]) -> i64 {
        let bits: usize = pieces.iter().map(|p| p.1).sum();
        let v = field(sf, pieces) as i64;
        if v >> (bits - 1) == 1 { v - (1 << bits) } else { v }
    }

    /// The broadcast ephemeris's parameters in SI units (angles in rad).
    #[derive(Debug)]
    struct Decoded {
        week10: u64,
        ura: u64,
        health: u64,
        iodc: u64,
        tgd: f64,
        toc: f64,
        af: [f64; 3],
        iode2: u64,
        iode3: u64,
        crs: f64,
        dn: f64,
        m0: f64,
        cuc: f64,
        e: f64,
        cus: f64,
        sqrt_a: f64,
        toe: f64,
        cic: f64,
        omega0: f64,
        cis: f64,
        i0: f64,
        crc: f64,
        omega: f64,
        omega_dot: f64,
        idot: f64,
    }

    /// Subframes 1, 2, 3 decoded with the bit positions and scale factors of
    /// IS-GPS-200 Figure 20-1 and Table 20-III.
    fn decode(sf1: &[u8], sf2: &[u8], sf3: &[u8]) -> Decoded {
        let p = |n: i32| 2f64.powi(n);
        let sc = |v: i64, n: i32| v as f64 * p(n) * PI;
        Decoded {
            week10: field(sf1, &[(61, 10)]),
            ura: field(sf1, &[(73, 4)]),
            health: field(sf1, &[(77, 6)]),
            iodc: field(sf1, &[(83, 2), (211, 8)]),
            tgd: signed(sf1, &[(197, 8)]) as f64 * p(-31),
            toc: field(sf1, &[(219, 16)]) as f64 * 16.0,
            af: [
                signed(sf1, &[(271, 22)]) as f64 * p(-31),
                signed(sf1, &[(249, 16)]) as f64 * p(-43),
                signed(sf1, &[(241, 8)]) as f64 * p(-55),
            ],
            iode2: field(sf2, &[(61, 8)]),
            crs: signed(sf2, &[(69, 16)]) as f64 * p(-5),
            dn: sc(signed(sf2, &[(91, 16)]), -43),
            m0: sc(signed(sf2, &[(107, 8), (121, 24)]), -31),
            cuc: signed(sf2, &[(151, 16)]) as f64 * p(-29),
            e: field(sf2, &[(167, 8), (181, 24)]) as f64 * p(-33),
            cus: signed(sf2, &[(211, 16)]) as f64 * p(-29),
            sqrt_a: field(sf2, &[(227, 8), (241, 24)]) as f64 * p(-19),
            toe: field(sf2, &[(271, 16)]) as f64 * 16.0,
            cic: signed(sf3, &[(61, 16)]) as f64 * p(-29),
            omega0: sc(signed(sf3, &[(77, 8), (91, 24)]), -31),
            cis: signed(sf3, &[(121, 16)]) as f64 * p(-29),
            i0: sc(signed(sf3, &[(137, 8), (151, 24)]), -31),
            crc: signed(sf3, &[(181, 16)]) as f64 * p(-5),
            omega: sc(signed(sf3, &[(197, 8), (211, 24)]), -31),
            omega_dot: sc(signed(sf3, &[(241, 24)]), -43),
            iode3: field(sf3, &[(271, 8)]),
            idot: sc(signed(sf3, &[(279, 14)]), -43),
        }
    }

    /// The satellite's ECEF position at GPS time of week `t` by the user
    /// algorithm of IS-GPS-200 Table 20-IV (μ and Ω̇ₑ of §20.3.3.4.3).
    fn icd_position(d: &Decoded, t: f64) -> [f64; 3] {
        let (mu, we) = (3.986005e14, 7.2921151467e-5);
        let a = d.sqrt_a * d.sqrt_a;
        let n = (mu / (a * a * a)).sqrt() + d.dn;
        let mut tk = t - d.toe;
        if tk > 302_400.0 {
            tk -= 604_800.0;
        } else if tk < -302_400.0 {
            tk += 604_800.0;
        }
        let mk = d.m0 + n * tk;
        let mut ek = mk;
        for _ in 0..30 {
            ek = mk + d.e * ek.sin();
        }
        let vk = ((1.0 - d.e * d.e).sqrt() * ek.sin()).atan2(ek.cos() - d.e);
        let phi = vk + d.omega;
        let (s2, c2) = (2.0 * phi).sin_cos();
        let uk = phi + d.cus * s2 + d.cuc * c2;
        let rk = a * (1.0 - d.e * ek.cos()) + d.crs * s2 + d.crc * c2;
        let ik = d.i0 + d.idot * tk + d.cis * s2 + d.cic * c2;
        let (xp, yp) = (rk * uk.cos(), rk * uk.sin());
        let om = d.omega0 + (d.omega_dot - we) * tk - we * d.toe;
        [xp * om.cos() - yp * ik.cos() * om.sin(), xp * om.sin() + yp * ik.cos() * om.cos(), yp * ik.sin()]
    }

    #[test]
    fn ephemeris_decodes_back_to_the_simulated_orbit() {
        use crate::satellites::{Constellation, GpsTime};
        let c = Constellation::builtin();
        // Subframe 1 of 2024-02-08 12:00:00 GPS (week 2300, TOW 388 800 s); t_oe then, two hours
        // later or two days later (19 h to 67 h from the almanac's t_oa).
        let start = (2300 * SUBFRAMES_PER_WEEK + 388_800 / 6) as f64 * 6.0;
        for (sat, toe) in
            c.satellites().iter().zip([start, start + 7200.0, start + 2.0 * 86_400.0 + 100.0].iter().cycle())
        {
            let eph = Ephemeris::of_orbit(sat, *toe).unwrap();
            assert_eq!(eph.toe_gps_s() % 16.0, 0.0);
            assert!((eph.toe_gps_s() - toe).abs() <= 8.0);
            let index = (start / 6.0) as i64;
            let mut d = (0, 0);
            let sfs: Vec<Vec<u8>> =
                (0..3).map(|k| received_subframe(&subframe_bits(index + k, Some(&eph)), &mut d)).collect();
            let dec = decode(&sfs[0], &sfs[1], &sfs[2]);
            // The fields a receiver checks and those sent as zero.
            assert_eq!(dec.week10, 2300 % 1024);
            assert_eq!((dec.ura, dec.health), (0, 0));
            assert_eq!(
                (dec.iodc, dec.iode2, dec.iode3),
                (u64::from(eph.iode), u64::from(eph.iode), u64::from(eph.iode))
            );
            assert_eq!((dec.tgd, dec.af), (0.0, [0.0; 3]));
            assert_eq!([dec.crs, dec.crc, dec.cuc, dec.cus, dec.cic, dec.cis, dec.dn, dec.idot], [0.0; 8]);
            let toe_tow = GpsTime::from_gps_seconds(eph.toe_gps_s()).tow_s;
            assert_eq!((dec.toe, dec.toc), (toe_tow, toe_tow));
            // The elements within half a scale factor of the almanac's (angles modulo a turn).
            let turn = |x: f64| (x + PI).rem_euclid(2.0 * PI) - PI;
            let half = |n: i32| 0.5 * 2f64.powi(n) * (1.0 + 1e-9);
            assert!((dec.e - sat.eccentricity).abs() <= half(-33));
            assert!((dec.sqrt_a - sat.sqrt_a_sqrtm).abs() <= half(-19));
            assert!(turn(dec.i0 - sat.inclination_rad).abs() <= half(-31) * PI);
            assert!(turn(dec.omega - sat.arg_perigee_rad).abs() <= half(-31) * PI);
            assert!((dec.omega_dot - sat.raan_rate_radps).abs() <= half(-43) * PI);
            // Positions over ±2 h of t_oe: the decoded message through the ICD's algorithm is the
            // broadcast orbit the IF generator uses to the µm, and the almanac's orbit to within
            // its quantization (half a scale factor of each element: a few cm).
            for k in -4..=4 {
                let t = eph.toe_gps_s() + f64::from(k) * 1800.0;
                let icd = icd_position(&dec, GpsTime::from_gps_seconds(t).tow_s);
                let dist =
                    |p: [f64; 3]| ((icd[0] - p[0]).powi(2) + (icd[1] - p[1]).powi(2) + (icd[2] - p[2]).powi(2)).sqrt();
                let broadcast = dist(eph.orbit().state_ecef(t).pos_m);
                assert!(broadcast < 1e-4, "PRN {} t_k {k}·30 min: {broadcast} m from the broadcast orbit", sat.prn);
                let almanac = dist(sat.state_ecef(t).pos_m);
                assert!(almanac < 0.15, "PRN {} t_k {k}·30 min: {almanac} m from the almanac's orbit", sat.prn);
            }
        }
    }

    #[test]
    fn an_orbit_beyond_the_fields_is_refused_by_name() {
        let c = crate::satellites::Constellation::builtin();
        let sat = &c.satellites()[0];
        let toe = sat.toa_gps_s();
        let wild = AlmanacEntry { eccentricity: 1.5, ..sat.clone() };
        let e = Ephemeris::of_orbit(&wild, toe).unwrap_err();
        assert_eq!(e, EphemerisError::OutOfRange { prn: sat.prn, field: "e", value: 1.5 });
        assert_eq!(e.to_string(), format!("PRN {}: e = 1.5 does not fit the broadcast ephemeris's field", sat.prn));
        // Ω̇ has 24 bits of 2⁻⁴³ semicircles/s: ±3.7e-6 rad/s.
        let spinning = AlmanacEntry { raan_rate_radps: 4e-6, ..sat.clone() };
        assert!(matches!(
            Ephemeris::of_orbit(&spinning, toe),
            Err(EphemerisError::OutOfRange { field: "omega_dot", .. })
        ));
        let far = AlmanacEntry { sqrt_a_sqrtm: 9000.0, ..sat.clone() };
        assert!(matches!(Ephemeris::of_orbit(&far, toe), Err(EphemerisError::OutOfRange { field: "sqrt_a", .. })));
    }

    #[test]
    fn subframes_parse_back() {
        // 2024-02-08T12:00:00 GPS ≈ week 2300, TOW 388 800 s: subframe index.
        let start = 2300 * SUBFRAMES_PER_WEEK + 388_800 / 6;
        let (mut d29, mut d30) = (0, 0);
        for k in 0..12 {
            let bits = subframe_bits(start + k, None);
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
