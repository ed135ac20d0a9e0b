//! Fuzzes the device link's decoder (`beamfield::link`, docs/link-protocol.md) on streams the
//! harness builds from the fuzz bytes: frames with a correct CRC (so that mutations reach the
//! version, type, length and value checks), frames with a mutated CRC, and raw runs between
//! them, fed to `Decoder` in chunks whose sizes come from the input too.
//!
//! Record tags (one byte each, then the record's bytes):
//! - `0x00..=0x7F`: a frame. Bits 0–3 pick the type (0–8: the nine message types; 9–15: the
//!   next byte as the type byte); bit 4 leaves the CRC as the next 4 bytes instead of the right
//!   one; bit 5 takes the payload length from the next byte (mod 80) instead of the type's;
//!   bit 6 takes the version byte from the next byte instead of `link::VERSION`. Then 2 bytes
//!   of sequence number and the payload (zero-padded when the input runs out).
//! - `0x80..=0xFF`: a raw run of `tag & 0x7F` bytes, appended as they are (zeros included).
//!
//! Checks: no panic; the counters add up (bytes fed, frames + errors = results); the decoder
//! never holds more than `MAX_ENCODED_LEN` bytes; every decoded frame holds valid values (it
//! encodes again) and is byte for byte the run it came from (one encoding per value).
//!
//! Run: `cargo +nightly fuzz run link_decode seeds/link_decode` from `fuzz/`.

#![no_main]

use beamfield::link::{
    crc32, encode, Decoder, MessageType, MAX_ENCODED_LEN, MAX_WIRE_LEN, VERSION,
};
use libfuzzer_sys::fuzz_target;

const TYPES: [u8; 9] = [0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x81, 0x82, 0x83];

struct Input<'a>(&'a [u8]);

impl Input<'_> {
    fn byte(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }
    fn or_zero(&mut self) -> u8 {
        self.byte().unwrap_or(0)
    }
}

fn build(data: &[u8]) -> Vec<u8> {
    let mut input = Input(data);
    let mut out = Vec::new();
    while let Some(tag) = input.byte() {
        if tag & 0x80 != 0 {
            for _ in 0..(tag & 0x7F) {
                out.push(input.or_zero());
            }
            continue;
        }
        let sel = usize::from(tag & 0x0F);
        let msg_type = TYPES.get(sel).copied().unwrap_or_else(|| input.or_zero());
        let version = if tag & 0x40 != 0 { input.or_zero() } else { VERSION };
        let len = if tag & 0x20 != 0 {
            usize::from(input.or_zero() % 80)
        } else {
            MessageType::from_u8(msg_type).map_or(0, |t| t.payload_len())
        };
        let mut raw = vec![version, msg_type, input.or_zero(), input.or_zero()];
        for _ in 0..len {
            raw.push(input.or_zero());
        }
        let crc = if tag & 0x10 != 0 {
            [input.or_zero(), input.or_zero(), input.or_zero(), input.or_zero()]
        } else {
            crc32(&raw).to_le_bytes()
        };
        raw.extend_from_slice(&crc);
        let mut encoded = vec![0u8; cobs::max_encoding_length(raw.len())];
        let n = cobs::try_encode(&raw, &mut encoded).unwrap();
        out.extend_from_slice(&encoded[..n]);
        out.push(0);
    }
    out
}

fuzz_target!(|data: &[u8]| {
    let (sizes, body) = data.split_at(data.len().min(2));
    let stream = build(body);
    let chunk = 1 + usize::from(sizes.first().copied().unwrap_or(0) % 64);

    let mut decoder = Decoder::new();
    let mut results = 0usize;
    // Start of the run of bytes the next result comes from (after the previous delimiter or
    // the byte that made a run oversized).
    let mut run_start = 0usize;
    let mut fed = 0usize;
    for part in stream.chunks(chunk) {
        for &b in part {
            fed += 1;
            let Some(r) = decoder.push(b) else {
                if b == 0 {
                    run_start = fed;
                }
                continue;
            };
            results += 1;
            assert!(decoder.buffered() <= MAX_ENCODED_LEN);
            if let Ok(frame) = r {
                let mut again = [0u8; MAX_WIRE_LEN];
                let n = encode(frame.seq, &frame.message, &mut again)
                    .expect("a decoded frame holds only valid values");
                assert_eq!(
                    &again[..n],
                    &stream[run_start..fed],
                    "a decoded frame re-encodes to its own bytes"
                );
            }
            if b == 0 {
                run_start = fed;
            }
        }
        assert!(decoder.buffered() <= MAX_ENCODED_LEN);
    }
    let s = decoder.stats();
    assert_eq!(s.bytes as usize, stream.len());
    assert_eq!((s.frames + s.errors()) as usize, results);
});
