//! The unit tests of `log::repair::lz4` (`src/log/repair/lz4.rs`).

// The source module's own imports.

use std::io::Write;

use lz4::liblz4::{BlockChecksum, BlockMode, BlockSize, ContentChecksum};
use proptest::prelude::*;

use ricochet::log::repair::lz4::decompress_prefix;

/// Compressible text with repeats near and far (JSON-like lines), `n` bytes.
fn text(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    let mut out = Vec::with_capacity(n + 64);
    while out.len() < n {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let line = format!(
            "{{\"t\":{},\"q\":[{:.6},{}],\"mode\":\"{}\"}}\n",
            x >> 40,
            (x >> 20) as f64 / 1e6,
            x % 97,
            ["closed", "open", "sliding"][(x % 3) as usize]
        );
        out.extend_from_slice(line.as_bytes());
    }
    out.truncate(n);
    out
}

/// `data` as one LZ4 frame, as mcap writes it (defaults, block checksums off) or with
/// every option of the frame format on.
fn frame(data: &[u8], all_options: bool) -> Vec<u8> {
    let mut builder = lz4::EncoderBuilder::new();
    if all_options {
        builder
            .block_size(BlockSize::Max256KB)
            .block_mode(BlockMode::Independent)
            .block_checksum(BlockChecksum::BlockChecksumEnabled)
            .checksum(ContentChecksum::ChecksumEnabled)
            .content_size(data.len() as u64);
    } else {
        builder.block_checksum(BlockChecksum::NoBlockChecksum);
    }
    let mut encoder = builder.build(Vec::new()).unwrap();
    encoder.write_all(data).unwrap();
    let (bytes, result) = encoder.finish();
    result.unwrap();
    bytes
}

/// Whole frames decode to their data; a frame cut anywhere decodes to a prefix of it,
/// never shorter than at an earlier cut; a cut inside the last block decodes more than
/// the blocks before it.
#[test]
fn a_cut_frame_decodes_to_a_growing_prefix() {
    for all_options in [false, true] {
        let data = text(300_000, 7);
        let bytes = frame(&data, all_options);
        assert_eq!(decompress_prefix(&bytes, data.len()), data);
        let mut previous = 0;
        for cut in (0..bytes.len()).step_by(61) {
            let out = decompress_prefix(&bytes[..cut], data.len());
            assert!(data.starts_with(&out), "cut {cut}: not a prefix");
            assert!(
                out.len() >= previous,
                "cut {cut}: {} < {previous}",
                out.len()
            );
            previous = out.len();
        }
        // Half of the frame gives about half of the data, not a block boundary.
        let half = decompress_prefix(&bytes[..bytes.len() / 2], data.len()).len();
        assert!(!half.is_multiple_of(65536), "{half}");
        assert!(half > data.len() / 4 && half < 3 * data.len() / 4, "{half}");
    }
}

/// Data that does not compress is stored in uncompressed blocks, cut the same way.
#[test]
fn stored_blocks_are_cut_too() {
    let mut x = 1u64;
    let data: Vec<u8> = (0..100_000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    let bytes = frame(&data, false);
    assert_eq!(decompress_prefix(&bytes, data.len()), data);
    let out = decompress_prefix(&bytes[..bytes.len() - 1000], data.len());
    assert!(
        data.starts_with(&out) && out.len() > 90_000,
        "{}",
        out.len()
    );
}

/// The output never grows past the limit.
#[test]
fn the_limit_holds() {
    let data = text(50_000, 3);
    let bytes = frame(&data, false);
    let out = decompress_prefix(&bytes, 1000);
    assert!(out.len() <= 1000 && data.starts_with(&out));
}

proptest! {
    /// Bytes that are not a frame, or a frame with bytes changed, never panic and stay
    /// within the limit.
    #[test]
    fn damaged_input_does_not_panic(
        garbage in proptest::collection::vec(any::<u8>(), 0..400),
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..8),
    ) {
        prop_assert!(decompress_prefix(&garbage, 10_000).len() <= 10_000);
        // A valid frame header (magic, FLG, BD, checksum), then garbage blocks.
        let mut blocks = frame(b"", false)[..7].to_vec();
        blocks.extend_from_slice(&garbage);
        prop_assert!(decompress_prefix(&blocks, 10_000).len() <= 10_000);
        let mut bytes = frame(&text(5000, 11), false);
        for (at, value) in flips {
            let n = bytes.len();
            bytes[at % n] = value;
        }
        prop_assert!(decompress_prefix(&bytes, 5000).len() <= 5000);
    }
}
