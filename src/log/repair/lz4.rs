//! Decoding as much of a cut-short LZ4 frame as its bytes allow.
//!
//! mcap compresses each chunk into one LZ4 frame [LZ4F] of linked blocks of at most 64 KiB
//! (the `lz4` crate's defaults, block checksums off). liblz4's streaming decoder, which
//! mcap's readers use, only outputs a compressed block once the whole block is there, so a
//! chunk cut short in its last (often only) block yields nothing through it. This decoder
//! walks the block's sequences [LZ4B] instead and stops at the first one whose bytes are
//! missing: its output is the exact prefix of the chunk's records that the bytes hold.
//!
//! [LZ4F] LZ4 Frame Format Description, v1.6.4, <https://github.com/lz4/lz4/blob/dev/doc/lz4_Frame_format.md>.
//! [LZ4B] LZ4 Block Format Description, <https://github.com/lz4/lz4/blob/dev/doc/lz4_Block_format.md>.

use super::scan::Bytes;

/// The magic number that opens an LZ4 frame [LZ4F, §General Structure].
const FRAME_MAGIC: u32 = 0x184D_2204;

/// The magic numbers of skippable frames, `0x184D2A50..=0x184D2A5F` [LZ4F, §Skippable Frames].
const SKIPPABLE: std::ops::RangeInclusive<u32> = 0x184D_2A50..=0x184D_2A5F;

/// The shortest match [LZ4B, §Sequence]: a match length field of 0 means 4 bytes.
const MIN_MATCH: usize = 4;

/// Decompresses the LZ4 frames of `input` as far as its bytes go: every complete block,
/// then the complete sequences of a block cut short, and the literals of a sequence cut
/// inside them. Never fails: at the first byte that is missing or malformed it stops and
/// returns what was decoded until then, at most `limit` bytes.
///
/// Checksums (header, block, content) are skipped, not verified: the MCAP chunk's CRC
/// covers a complete chunk, and nothing can vouch for the prefix of a torn one.
#[doc(hidden)]
pub fn decompress_prefix(input: &[u8], limit: usize) -> Vec<u8> {
    let mut out = Vec::new();
    let mut rest = Bytes(input);
    while !rest.0.is_empty() && frame(&mut rest, &mut out, limit).is_some() {}
    out
}

/// Decodes one frame at the start of `r` into `out`; `Some` if the whole frame was there
/// and well formed (`r` then starts after it).
fn frame(r: &mut Bytes<'_>, out: &mut Vec<u8>, limit: usize) -> Option<()> {
    let magic = r.u32()?;
    if SKIPPABLE.contains(&magic) {
        let size = r.u32()?;
        r.take(usize::try_from(size).ok()?)?;
        return Some(());
    }
    if magic != FRAME_MAGIC {
        return None;
    }
    // Frame descriptor [LZ4F, §Frame Descriptor]: FLG, BD, content size, dictionary id,
    // header checksum.
    let flg = r.u8()?;
    let _bd = r.u8()?;
    let version = flg >> 6;
    let independent = flg & 0x20 != 0;
    let block_checksum = flg & 0x10 != 0;
    let content_size = flg & 0x08 != 0;
    let content_checksum = flg & 0x04 != 0;
    let dictionary = flg & 0x01 != 0;
    // A dictionary is not in the file: a frame that needs one cannot be decoded.
    if version != 1 || dictionary {
        return None;
    }
    if content_size {
        r.take(8)?;
    }
    r.take(1)?;
    // Blocks [LZ4F, §Data Blocks]: a size (bit 31: stored uncompressed), the data, an
    // optional checksum; a size of 0 ends the frame.
    let frame_start = out.len();
    loop {
        let size = r.u32()?;
        if size == 0 {
            break;
        }
        let stored = size & 0x8000_0000 != 0;
        let size = usize::try_from(size & 0x7FFF_FFFF).ok()?;
        let data = r.take_up_to(size);
        // Linked blocks may copy from every earlier block of the frame; independent ones
        // from their own output only.
        let window_start = if independent { out.len() } else { frame_start };
        let decoded = if stored {
            let room = limit.saturating_sub(out.len());
            out.extend_from_slice(&data[..data.len().min(room)]);
            data.len() <= room
        } else {
            block(data, out, window_start, limit)
        };
        if !decoded || data.len() < size {
            return None;
        }
        if block_checksum {
            r.take(4)?;
        }
    }
    if content_checksum {
        r.take(4)?;
    }
    Some(())
}

/// Decodes the compressed block `data` [LZ4B] into `out`; `true` if it decoded whole and
/// well formed. Matches may reach back to `out[window_start..]`; `out` never grows past
/// `limit` bytes.
///
/// A block is a series of sequences, each: a token (literal length in its high 4 bits,
/// match length − 4 in its low 4; 15 means more length bytes follow, each added, until
/// one is not 255), the literals, a 2-byte little-endian offset, the match length bytes.
/// The last sequence has literals only.
fn block(data: &[u8], out: &mut Vec<u8>, window_start: usize, limit: usize) -> bool {
    let mut r = Bytes(data);
    loop {
        let Some(token) = r.u8() else {
            return false;
        };
        // Literals, possibly cut short: those that are there are output.
        let Some(n) = length(&mut r, token >> 4) else {
            return false;
        };
        let literals = r.take_up_to(n);
        if out.len() + literals.len() > limit {
            return false;
        }
        out.extend_from_slice(literals);
        if literals.len() < n {
            return false;
        }
        if r.0.is_empty() {
            return true;
        }
        // The match: copy `m` bytes from `offset` back, byte by byte when they overlap.
        let Some(offset) = r.u16().map(usize::from) else {
            return false;
        };
        let Some(m) = length(&mut r, token & 0x0F).map(|m| m + MIN_MATCH) else {
            return false;
        };
        if offset == 0 || offset > out.len() - window_start || out.len() + m > limit {
            return false;
        }
        let start = out.len() - offset;
        if offset >= m {
            out.extend_from_within(start..start + m);
        } else {
            for k in start..start + m {
                out.push(out[k]);
            }
        }
    }
}

/// A literal or match length: the token's 4-bit `nibble`, plus the bytes that follow it
/// when it is 15 [LZ4B, §Token].
fn length(r: &mut Bytes<'_>, nibble: u8) -> Option<usize> {
    let mut n = usize::from(nibble);
    if nibble == 15 {
        loop {
            let b = r.u8()?;
            n = n.checked_add(usize::from(b))?;
            if b != 255 {
                break;
            }
        }
    }
    Some(n)
}
