//! The file's identity: the UUID in a VDB header (step 6 of the layout in
//! [`super::write`]). OpenVDB draws it at random; we derive it from a hash of
//! every piece of the file after the header ([`content_uuid`] over
//! [`piece_hash`]es), so identical inputs give byte-identical files. The hash
//! is XXH64, written here (checked against libxxhash in the tests) so that
//! UUIDs never change with a dependency or the toolchain.

/// The 128-bit hash of one piece of the file: XXH64 (Yann Collet's
/// xxHash, 64-bit variant) with two seeds. Not cryptographic: it only has to
/// make distinct files get distinct UUIDs, and XXH64 is a well-tested,
/// fixed, fast algorithm (so UUIDs never change with the toolchain).
pub fn piece_hash(data: &[u8]) -> (u64, u64) {
    (xxh64(data, 0), xxh64(data, 0x9E37_79B9_7F4A_7C15))
}

const P1: u64 = 0x9E37_79B1_85EB_CA87;
const P2: u64 = 0xC2B2_AE3D_27D4_EB4F;
const P3: u64 = 0x1656_67B1_9E37_79F9;
const P4: u64 = 0x85EB_CA77_C2B2_AE63;
const P5: u64 = 0x27D4_EB2F_1656_67C5;

/// One XXH64 round: `acc += input * P2; acc = rotl(acc, 31); acc *= P1`.
#[inline(always)]
fn xxh_round(acc: u64, input: u64) -> u64 {
    acc.wrapping_add(input.wrapping_mul(P2)).rotate_left(31).wrapping_mul(P1)
}

/// XXH64 of `data` with `seed` (the reference algorithm, checked against
/// libxxhash in the tests).
pub fn xxh64(data: &[u8], seed: u64) -> u64 {
    let u64_at = |b: &[u8]| u64::from_le_bytes(b[..8].try_into().expect("8 bytes"));
    let mut rest = data;
    let mut h = if data.len() >= 32 {
        let mut v = [seed.wrapping_add(P1).wrapping_add(P2), seed.wrapping_add(P2), seed, seed.wrapping_sub(P1)];
        let mut stripes = data.chunks_exact(32);
        for s in &mut stripes {
            for (k, lane) in v.iter_mut().enumerate() {
                *lane = xxh_round(*lane, u64_at(&s[8 * k..]));
            }
        }
        rest = stripes.remainder();
        let mut h =
            v[0].rotate_left(1).wrapping_add(v[1].rotate_left(7)).wrapping_add(v[2].rotate_left(12)).wrapping_add(v[3].rotate_left(18));
        for lane in v {
            h = (h ^ xxh_round(0, lane)).wrapping_mul(P1).wrapping_add(P4);
        }
        h
    } else {
        seed.wrapping_add(P5)
    };
    h = h.wrapping_add(data.len() as u64);
    while rest.len() >= 8 {
        h = (h ^ xxh_round(0, u64_at(rest))).rotate_left(27).wrapping_mul(P1).wrapping_add(P4);
        rest = &rest[8..];
    }
    if rest.len() >= 4 {
        let w = u32::from_le_bytes(rest[..4].try_into().expect("4 bytes")) as u64;
        h = (h ^ w.wrapping_mul(P1)).rotate_left(23).wrapping_mul(P2).wrapping_add(P3);
        rest = &rest[4..];
    }
    for &b in rest {
        h = (h ^ (b as u64).wrapping_mul(P5)).rotate_left(11).wrapping_mul(P1);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(P2);
    h ^= h >> 29;
    h = h.wrapping_mul(P3);
    h ^ (h >> 32)
}

/// A UUID (RFC 9562 version 8, "custom") from the hashes of the file's pieces
/// after the header, in order (their boundaries are fixed by the content:
/// headers, topology, chunks of 64 leaves; the descriptor offsets are hashed
/// as zeros). Formatted 8-4-4-4-12 in lowercase hex. Identical inputs give
/// identical UUIDs whatever the thread count.
pub fn content_uuid(piece_hashes: &[(u64, u64)]) -> String {
    let mut a = 0xA409_3822_299F_31D0u64 ^ piece_hashes.len() as u64;
    let mut b = 0x082E_FA98_EC4E_6C89u64;
    for &(x, y) in piece_hashes {
        a = mix(a ^ x);
        b = mix(b ^ y);
    }
    let mut u = ((a as u128) << 64) | b as u128;
    u = (u & !(0xF << 76)) | (0x8 << 76); // version 8
    u = (u & !(0x3 << 62)) | (0x2 << 62); // variant 10
    let h = format!("{u:032x}");
    format!("{}-{}-{}-{}-{}", &h[0..8], &h[8..12], &h[12..16], &h[16..20], &h[20..32])
}

/// splitmix64 finaliser.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// XXH64 against libxxhash 0.8.1 (`XXH64` through ctypes), for every
    /// code path: empty, byte tail, 4-byte tail, 8-byte words, 32-byte stripes.
    #[test]
    fn xxh64_matches_reference() {
        let data: Vec<u8> = (0..1000u32).map(|i| ((i * 7 + 3) & 0xff) as u8).collect();
        let expect: [(usize, u64, u64); 13] = [
            (0, 0xef46db3751d8e999, 0xc4349fc93c010000),
            (1, 0x1f25c8d0bc1f4bb6, 0x79826bcd749d267a),
            (3, 0x31d2363f52e564c9, 0x78efd77575e26575),
            (4, 0x9bb64b7d66ee9fda, 0x6f0a6c97d68bf353),
            (7, 0x9a7b149959ce60d8, 0xd97ede93c9d66a0d),
            (8, 0xdab99d95c6f90092, 0xa2f1e28437a78a1b),
            (15, 0x1b47cb8243cc8e32, 0xe2ec50a544faec61),
            (31, 0xa2aa5f33cc4a6119, 0x755437271d1d0a84),
            (32, 0x23c3c17ef790fd97, 0xbf624b932c090428),
            (33, 0x50a7cfc7ba588784, 0x7aceaf1e9d34ea35),
            (63, 0x5e3e54b431c7493c, 0x2c8ddce5c85d0d9d),
            (100, 0xa61f8d4c170fe531, 0xf6d8f65c625abb4f),
            (1000, 0x5f235fa033f1a3fb, 0x442acd0a822e86f6),
        ];
        for (n, a, b) in expect {
            assert_eq!(piece_hash(&data[..n]), (a, b), "length {n}");
        }
    }

    /// Every length of zeros and every single-bit change of a 100-byte
    /// buffer give distinct piece hashes (lanes, tail and length all count).
    #[test]
    fn piece_hash_separates_lengths_and_bits() {
        let mut seen = std::collections::HashMap::new();
        for n in 0..100 {
            let h = piece_hash(&vec![0u8; n]);
            if let Some(o) = seen.insert(h, format!("zeros {n}")) {
                panic!("length {n} collides with {o}");
            }
        }
        let base: Vec<u8> = (0..100u8).collect();
        for i in 0..100 {
            for b in 0..8 {
                let mut v = base.clone();
                v[i] ^= 1 << b;
                if let Some(o) = seen.insert(piece_hash(&v), format!("bit {b} of byte {i}")) {
                    panic!("bit {b} of byte {i} collides with {o}");
                }
            }
        }
    }

    #[test]
    fn uuid_is_well_formed_and_content_dependent() {
        let a = content_uuid(&[piece_hash(b"hello")]);
        assert_ne!(a, content_uuid(&[piece_hash(b"hellp")]));
        assert_ne!(a, content_uuid(&[piece_hash(b"hel"), piece_hash(b"lo")]));
        assert_eq!(a, content_uuid(&[piece_hash(b"hello")]));
        assert_eq!(a.len(), 36);
        assert!(matches!(a.as_bytes()[19], b'8' | b'9' | b'a' | b'b'));
    }
}
