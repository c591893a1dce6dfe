#pragma once
// Correction files (.mfc, DESIGN §6, thesis §4.3.2): the edits that turn a base mesh into a
// result, named by the SHA-256 of both (over their canonical PLY bytes), compressed.
//
// Layout: "MFC1" magic, version byte (2), 32-byte SHA-256 of the base, 32-byte SHA-256 of the
// result, u64 payload size, u32 edit count, then one zstd frame holding six streams (opcodes;
// varint ids, delta-coded; raw float32 positions; zigzag float32 bit deltas; flags; corner
// codes), positions and deltas split into byte planes so that small moves compress to little.
// A move is coded against the vertex's current position, or, in MoveAllVertices, against the
// umbrella prediction (the average of its current neighbours) when that is closer: one flag
// bit a vertex says which. An added vertex is coded against the previous added vertex; an
// added triangle's corner is one byte when it is in a 16-entry move-to-front cache of recent
// corners or the next added vertex used for the first time, else that byte and its id. Both
// sides compute predictions and caches on the same mesh state and edits, so it is lossless.
// The encoder is deterministic. Decoding is safe for untrusted
// input: bad magic, unknown version, truncation, trailing bytes and absurd counts are refused
// with InvalidInput, never a crash.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "protocol/edits.h"

namespace meshflow::protocol {

struct CorrectionHeader {
  std::string base_sha256;    // lowercase hex
  std::string result_sha256;  // lowercase hex
  std::uint32_t edit_count = 0;
};

// Encodes `edits`, which must apply to `base` (moves are coded against the positions they
// replace). \throws InvalidInput when an edit does not apply.
std::vector<std::uint8_t> encode_correction(const mesh::Mesh& base, const std::string& base_sha256,
                                            const std::string& result_sha256, const EditList& edits);

// The header alone (what a correction applies to and yields). \throws InvalidInput.
CorrectionHeader read_correction_header(std::span<const std::uint8_t> bytes);

// Decodes the edits against `base` (the mesh they apply to). \throws InvalidInput.
EditList decode_correction(const mesh::Mesh& base, std::span<const std::uint8_t> bytes);

// Applies a correction: checks the base's hash first and the result's after; on any mismatch
// throws InvalidInput saying which hash differs, and returns nothing half-patched.
mesh::Mesh apply_correction(const mesh::Mesh& base, std::span<const std::uint8_t> bytes);

}  // namespace meshflow::protocol
