#include "protocol/correction.h"

#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "protocol/edit_mesh.h"

namespace meshflow::protocol {
namespace {

constexpr char kMagic[4] = {'M', 'F', 'C', '1'};
constexpr std::uint8_t kVersion = 2;  // 2: AddTriangle corners and AddVertex positions predicted
constexpr std::size_t kHeaderSize = 4 + 1 + 32 + 32 + 8 + 4;
constexpr std::uint64_t kMaxPayload = 1ull << 34;  // 16 GiB: anything bigger is not ours
constexpr std::uint8_t kHasPoint = 0x80;
enum Stream { kOps, kIds, kPositions, kDeltas, kFlags, kCorners, kStreams };

// The corners of added triangles (a hole's patch, a region re-triangulated) mostly repeat a
// vertex of the last few triangles or introduce the next vertex added: one byte says which,
// and only the other corners are written as ids. Encoder and decoder keep the same state.
constexpr std::uint8_t kCornerCacheSize = 16;
constexpr std::uint8_t kCornerExplicit = kCornerCacheSize;  // an id follows in the id stream
constexpr std::uint8_t kCornerFresh = kCornerCacheSize + 1;  // the next added vertex, first use
class CornerModel {
 public:
  explicit CornerModel(Index first_added) : fresh_(first_added) {}
  // The code for corner v, and the state updated as if it had been coded.
  std::uint8_t code(Index v) {
    std::uint8_t c = kCornerExplicit;
    if (v == fresh_) c = kCornerFresh;
    else
      for (std::uint8_t i = 0; i < cache_size_; ++i)
        if (cache_[i] == v) c = i;
    see(v, c);
    return c;
  }
  // The corner a code stands for (explicit: `explicit_id`), state updated. False: a bad code.
  bool corner(std::uint8_t c, Index explicit_id, Index& v) {
    if (c == kCornerFresh) v = fresh_;
    else if (c == kCornerExplicit) v = explicit_id;
    else if (c < cache_size_) v = cache_[c];
    else return false;
    see(v, c);
    return true;
  }

 private:
  void see(Index v, std::uint8_t c) {
    if (c == kCornerFresh) ++fresh_;
    std::uint8_t at = c < cache_size_ ? c : std::min<std::uint8_t>(cache_size_, kCornerCacheSize - 1);
    if (c >= cache_size_ && cache_size_ < kCornerCacheSize) ++cache_size_;
    for (std::uint8_t i = at; i > 0; --i) cache_[i] = cache_[i - 1];  // move to front
    cache_[0] = v;
  }
  Index fresh_;
  std::array<Index, kCornerCacheSize> cache_{};
  std::uint8_t cache_size_ = 0;
};

// ---- encoding helpers ----
// The umbrella prediction of every live vertex: the average of its edge neighbours (ascending
// ids, summed in double, rounded once), or its own position when it has none. Encoder and
// decoder compute it on the same mesh state, so it is identical on both sides.
std::vector<Point> umbrella_predictions(const EditMesh& mesh) {
  std::size_t V = mesh.vertex_slots();
  std::vector<std::uint64_t> keys;
  for (std::size_t t = 0; t < mesh.triangle_slots(); ++t) {
    if (!mesh.triangle_alive(static_cast<Index>(t))) continue;
    const auto& tri = mesh.triangle(static_cast<Index>(t));
    for (int k = 0; k < 3; ++k) {
      Index a = tri[k], b = tri[(k + 1) % 3];
      if (a == b) continue;
      keys.push_back(static_cast<std::uint64_t>(std::min(a, b)) << 32 | std::max(a, b));
      keys.push_back(static_cast<std::uint64_t>(std::max(a, b)) << 32 | std::min(a, b));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Point> out;
  std::size_t at = 0;
  for (std::size_t v = 0; v < V; ++v) {
    double sum[3] = {0, 0, 0};
    std::size_t n = 0;
    for (; at < keys.size() && (keys[at] >> 32) == v; ++at, ++n) {
      const Point& p = mesh.position(static_cast<Index>(keys[at] & 0xffffffff));
      for (int k = 0; k < 3; ++k) sum[k] += p[k];
    }
    if (!mesh.vertex_alive(static_cast<Index>(v))) continue;
    if (n == 0) out.push_back(mesh.position(static_cast<Index>(v)));
    else out.push_back({static_cast<float>(sum[0] / double(n)), static_cast<float>(sum[1] / double(n)),
                        static_cast<float>(sum[2] / double(n))});
  }
  return out;
}

std::uint32_t zigzag_delta(float from, float to) {
  auto d = static_cast<std::int32_t>(std::bit_cast<std::uint32_t>(to) - std::bit_cast<std::uint32_t>(from));
  return (static_cast<std::uint32_t>(d) << 1) ^ static_cast<std::uint32_t>(d >> 31);
}

struct Streams {
  std::vector<std::uint8_t> flags;
  std::size_t flag_bits = 0;
  void flag(bool on) {
    if (flag_bits % 8 == 0) flags.push_back(0);
    if (on) flags.back() |= static_cast<std::uint8_t>(1u << (flag_bits % 8));
    ++flag_bits;
  }
  std::vector<std::uint8_t> ops, ids, corners;
  std::vector<std::uint32_t> positions, deltas;
  Index previous_id = 0;
  Point previous_added{0, 0, 0};  // AddVertex positions are coded against the previous one

  void id(Index value) {
    auto delta = static_cast<std::int64_t>(value) - static_cast<std::int64_t>(previous_id);
    previous_id = value;
    varint(static_cast<std::uint64_t>((delta << 1) ^ (delta >> 63)));
  }
  void varint(std::uint64_t v) {
    while (v >= 0x80) {
      ids.push_back(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    ids.push_back(static_cast<std::uint8_t>(v));
  }
  void point(const Point& p) {
    for (float c : p) positions.push_back(std::bit_cast<std::uint32_t>(c));
  }
  void move(const Point& from, const Point& to) {
    for (int k = 0; k < 3; ++k) deltas.push_back(zigzag_delta(from[k], to[k]));
  }
  // A move coded against whichever of the current position and the umbrella prediction is
  // closer (one flag bit a vertex says which).
  void predicted_move(const Point& current, const Point& predicted, const Point& to) {
    std::uint32_t plain = 0, guessed = 0;
    for (int k = 0; k < 3; ++k) {
      plain = std::max(plain, zigzag_delta(current[k], to[k]));
      guessed = std::max(guessed, zigzag_delta(predicted[k], to[k]));
    }
    bool use_prediction = guessed < plain;
    flag(use_prediction);
    move(use_prediction ? predicted : current, to);
  }
};

void append_planes(std::vector<std::uint8_t>& out, const std::vector<std::uint32_t>& values) {
  std::size_t base = out.size();
  out.resize(base + values.size() * 4);
  for (int plane = 0; plane < 4; ++plane)
    for (std::size_t i = 0; i < values.size(); ++i)
      out[base + plane * values.size() + i] = static_cast<std::uint8_t>(values[i] >> (8 * plane));
}

void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

void hex_to_raw(const std::string& hex, std::uint8_t* out) {
  if (hex.size() != 64) throw InvalidInput("a SHA-256 must be 64 hex digits, got '" + hex + "'");
  for (int i = 0; i < 32; ++i) {
    auto nibble = [&](char c) -> int {
      if (c >= '0' && c <= '9') return c - '0';
      if (c >= 'a' && c <= 'f') return c - 'a' + 10;
      throw InvalidInput("not a lowercase hex SHA-256: '" + hex + "'");
    };
    out[i] = static_cast<std::uint8_t>(nibble(hex[2 * i]) << 4 | nibble(hex[2 * i + 1]));
  }
}

std::string raw_to_hex(const std::uint8_t* raw) {
  static const char* digits = "0123456789abcdef";
  std::string out(64, '0');
  for (int i = 0; i < 32; ++i) out[2 * i] = digits[raw[i] >> 4], out[2 * i + 1] = digits[raw[i] & 15];
  return out;
}

std::uint8_t opcode(const Edit& e) { return static_cast<std::uint8_t>(e.index()); }

// ---- decoding helpers ----
class Reader {
 public:
  Reader(std::span<const std::uint8_t> ops, std::span<const std::uint8_t> ids,
         std::span<const std::uint8_t> positions, std::span<const std::uint8_t> deltas,
         std::span<const std::uint8_t> flags, std::span<const std::uint8_t> corners)
      : ops_(ops), ids_(ids), positions_(positions), deltas_(deltas), flags_(flags), corners_(corners) {
    if (positions.size() % 12 || deltas.size() % 12)
      throw InvalidInput("correction: position streams are not whole float triples");
  }
  std::uint8_t op() {
    if (op_at_ >= ops_.size()) throw InvalidInput("correction: fewer operations than announced");
    return ops_[op_at_++];
  }
  std::uint64_t varint() {
    std::uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (id_at_ >= ids_.size()) throw InvalidInput("correction: truncated id stream");
      std::uint8_t b = ids_[id_at_++];
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    throw InvalidInput("correction: malformed varint");
  }
  Index id() {
    std::uint64_t z = varint();
    std::int64_t delta = static_cast<std::int64_t>(z >> 1) ^ -static_cast<std::int64_t>(z & 1);
    std::int64_t value = static_cast<std::int64_t>(previous_id_) + delta;
    if (value < 0 || value > 0xFFFFFFFFll) throw InvalidInput("correction: id out of range");
    previous_id_ = static_cast<Index>(value);
    return previous_id_;
  }
  Point point() {
    std::size_t n = positions_.size() / 4;
    if (pos_at_ + 3 > n) throw InvalidInput("correction: truncated position stream");
    Point p;
    for (int k = 0; k < 3; ++k) p[k] = std::bit_cast<float>(plane_value(positions_, n, pos_at_++));
    return p;
  }
  Point moved(const Point& from) {
    std::size_t n = deltas_.size() / 4;
    if (delta_at_ + 3 > n) throw InvalidInput("correction: truncated move stream");
    Point p;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t z = plane_value(deltas_, n, delta_at_++);
      std::uint32_t d = (z >> 1) ^ (0u - (z & 1));
      p[k] = std::bit_cast<float>(std::bit_cast<std::uint32_t>(from[k]) + d);
    }
    return p;
  }
  std::uint8_t corner_code() {
    if (corner_at_ >= corners_.size()) throw InvalidInput("correction: truncated corner stream");
    return corners_[corner_at_++];
  }
  bool flag() {
    if (flag_at_ / 8 >= flags_.size()) throw InvalidInput("correction: truncated flag stream");
    bool on = (flags_[flag_at_ / 8] >> (flag_at_ % 8)) & 1;
    ++flag_at_;
    return on;
  }
  bool finished() const {
    return op_at_ == ops_.size() && id_at_ == ids_.size() && pos_at_ * 4 == positions_.size() &&
           delta_at_ * 4 == deltas_.size() && (flag_at_ + 7) / 8 == flags_.size() &&
           corner_at_ == corners_.size();
  }

 private:
  static std::uint32_t plane_value(std::span<const std::uint8_t> planes, std::size_t n, std::size_t i) {
    return planes[i] | planes[n + i] << 8 | planes[2 * n + i] << 16 |
           static_cast<std::uint32_t>(planes[3 * n + i]) << 24;
  }
  std::span<const std::uint8_t> ops_, ids_, positions_, deltas_, flags_, corners_;
  std::size_t op_at_ = 0, id_at_ = 0, pos_at_ = 0, delta_at_ = 0, flag_at_ = 0, corner_at_ = 0;
  Index previous_id_ = 0;
};

struct Parsed {
  CorrectionHeader header;
  std::vector<std::uint8_t> payload;
  std::span<const std::uint8_t> streams[kStreams];
};

Parsed parse(std::span<const std::uint8_t> bytes) {
  Parsed out;
  if (bytes.size() < kHeaderSize) throw InvalidInput("correction: truncated header (" + std::to_string(bytes.size()) + " bytes)");
  if (std::memcmp(bytes.data(), kMagic, 4) != 0) throw InvalidInput("correction: bad magic (not an .mfc file)");
  if (bytes[4] != kVersion) throw InvalidInput("correction: unknown version " + std::to_string(bytes[4]));
  out.header.base_sha256 = raw_to_hex(bytes.data() + 5);
  out.header.result_sha256 = raw_to_hex(bytes.data() + 37);
  std::uint64_t payload_size = get_u64(bytes.data() + 69);
  std::memcpy(&out.header.edit_count, bytes.data() + 77, 4);
  if (payload_size > kMaxPayload || payload_size < 8 * kStreams)
    throw InvalidInput("correction: implausible payload size " + std::to_string(payload_size));
  if (out.header.edit_count > payload_size) throw InvalidInput("correction: implausible edit count");
  auto frame = bytes.subspan(kHeaderSize);
  std::size_t frame_size = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  if (ZSTD_isError(frame_size)) throw InvalidInput("correction: truncated or corrupt compressed data");
  if (frame_size != frame.size()) throw InvalidInput("correction: " + std::to_string(frame.size() - frame_size) + " trailing bytes");
  unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (content != payload_size) throw InvalidInput("correction: payload size does not match its header");
  out.payload.resize(payload_size);
  std::size_t got = ZSTD_decompress(out.payload.data(), out.payload.size(), frame.data(), frame.size());
  if (ZSTD_isError(got) || got != payload_size) throw InvalidInput("correction: corrupt compressed data");
  std::size_t at = 8 * kStreams;
  for (int s = 0; s < kStreams; ++s) {
    std::uint64_t length = get_u64(out.payload.data() + 8 * s);
    if (length > payload_size - at) throw InvalidInput("correction: stream lengths exceed the payload");
    out.streams[s] = std::span<const std::uint8_t>(out.payload.data() + at, length);
    at += length;
  }
  if (at != payload_size) throw InvalidInput("correction: payload has bytes beyond its streams");
  if (out.streams[kOps].size() != out.header.edit_count) throw InvalidInput("correction: edit count does not match");
  return out;
}

// Decodes edit after edit, applying each to `mesh` (moves are relative to current positions).
void decode_into(const Parsed& parsed, EditMesh& mesh, EditList* edits) {
  Reader in(parsed.streams[kOps], parsed.streams[kIds], parsed.streams[kPositions], parsed.streams[kDeltas],
            parsed.streams[kFlags], parsed.streams[kCorners]);
  CornerModel corners(static_cast<Index>(mesh.vertex_slots()));
  Point previous_added{0, 0, 0};
  auto corner = [&]() {
    std::uint8_t c = in.corner_code();
    Index explicit_id = c == kCornerExplicit ? in.id() : 0;
    Index v = 0;
    if (!corners.corner(c, explicit_id, v)) throw InvalidInput("correction: bad corner code " + std::to_string(c));
    return v;
  };
  for (std::uint32_t i = 0; i < parsed.header.edit_count; ++i) {
    std::uint8_t code = in.op();
    bool has_point = code & kHasPoint;
    code &= static_cast<std::uint8_t>(~kHasPoint);
    Edit edit;
    auto optional_point = [&]() -> std::optional<Point> {
      if (has_point) return in.point();
      return std::nullopt;
    };
    switch (code) {
      case 0: { Index a = corner(), b = corner(), c = corner(); edit = AddTriangle{a, b, c}; break; }
      case 1: edit = RemoveTriangle{in.id()}; break;
      case 2: { Index t = in.id(); edit = SplitTriangle{t, optional_point()}; break; }
      case 3: previous_added = in.moved(previous_added); edit = AddVertex{previous_added}; break;
      case 4: edit = RemoveVertex{in.id()}; break;
      case 5: {
        Index v = in.id();
        if (!mesh.vertex_alive(v)) throw InvalidInput("correction: edit " + std::to_string(i) + " moves a dead vertex");
        edit = MoveVertex{v, in.moved(mesh.position(v))};
        break;
      }
      case 6: {
        std::uint64_t count = in.varint();
        if (count > mesh.vertex_slots()) throw InvalidInput("correction: MoveAllVertices count exceeds the vertices");
        std::vector<Point> predicted = umbrella_predictions(mesh);
        if (count != predicted.size()) throw InvalidInput("correction: MoveAllVertices count is not the live vertex count");
        std::vector<Point> positions;
        positions.reserve(count);
        for (std::size_t v = 0; v < mesh.vertex_slots() && positions.size() < count; ++v)
          if (mesh.vertex_alive(static_cast<Index>(v))) {
            const Point& guess = predicted[positions.size()];
            positions.push_back(in.moved(in.flag() ? guess : mesh.position(static_cast<Index>(v))));
          }
        edit = MoveAllVertices{std::move(positions)};
        break;
      }
      case 7: { Index a = in.id(), b = in.id(); edit = AddEdge{a, b}; break; }
      case 8: { Index a = in.id(), b = in.id(); edit = SwapEdge{a, b}; break; }
      case 9: { Index a = in.id(), b = in.id(); edit = CollapseEdge{a, b, optional_point()}; break; }
      case 10: { Index a = in.id(), b = in.id(); edit = SplitEdge{a, b, optional_point()}; break; }
      case 11: edit = ClearAll{}; break;
      default: throw InvalidInput("correction: unknown operation code " + std::to_string(code));
    }
    mesh.apply(edit, i);
    if (edits) edits->push_back(std::move(edit));
  }
  if (!in.finished()) throw InvalidInput("correction: streams hold data beyond the last operation");
}

}  // namespace

std::vector<std::uint8_t> encode_correction(const mesh::Mesh& base, const std::string& base_sha256,
                                            const std::string& result_sha256, const EditList& edits) {
  Streams s;
  EditMesh mesh(base);
  CornerModel corners(static_cast<Index>(base.positions.size()));
  for (std::size_t i = 0; i < edits.size(); ++i) {
    const Edit& edit = edits[i];
    std::uint8_t code = opcode(edit);
    std::visit(
        [&](const auto& e) {
          using E = std::decay_t<decltype(e)>;
          if constexpr (std::is_same_v<E, AddTriangle>) {
            for (Index v : {e.a, e.b, e.c}) {
              std::uint8_t c = corners.code(v);
              s.corners.push_back(c);
              if (c == kCornerExplicit) s.id(v);
            }
          }
          else if constexpr (std::is_same_v<E, RemoveTriangle>) s.id(e.t);
          else if constexpr (std::is_same_v<E, SplitTriangle>) { s.id(e.t); if (e.p) code |= kHasPoint, s.point(*e.p); }
          else if constexpr (std::is_same_v<E, AddVertex>) {
            s.move(s.previous_added, e.p);
            s.previous_added = e.p;
          }
          else if constexpr (std::is_same_v<E, RemoveVertex>) s.id(e.v);
          else if constexpr (std::is_same_v<E, MoveVertex>) {
            if (!mesh.vertex_alive(e.v)) throw InvalidInput("edit " + std::to_string(i) + ": MoveVertex of a dead vertex");
            s.id(e.v);
            s.move(mesh.position(e.v), e.p);
          } else if constexpr (std::is_same_v<E, MoveAllVertices>) {
            s.varint(e.positions.size());
            std::vector<Point> predicted = umbrella_predictions(mesh);
            if (predicted.size() != e.positions.size())
              throw InvalidInput("edit " + std::to_string(i) + ": MoveAllVertices count is not the live vertex count");
            std::size_t k = 0;
            for (std::size_t v = 0; v < mesh.vertex_slots() && k < e.positions.size(); ++v)
              if (mesh.vertex_alive(static_cast<Index>(v))) {
                s.predicted_move(mesh.position(static_cast<Index>(v)), predicted[k], e.positions[k]);
                ++k;
              }
          } else if constexpr (std::is_same_v<E, AddEdge> || std::is_same_v<E, SwapEdge>) { s.id(e.a); s.id(e.b); }
          else if constexpr (std::is_same_v<E, CollapseEdge> || std::is_same_v<E, SplitEdge>) {
            s.id(e.a); s.id(e.b);
            if (e.p) code |= kHasPoint, s.point(*e.p);
          }
        },
        edit);
    s.ops.push_back(code);
    mesh.apply(edit, i);  // validates, and keeps positions current for the next moves
  }
  std::vector<std::uint8_t> payload;
  std::vector<std::uint8_t> positions, deltas;
  append_planes(positions, s.positions);
  append_planes(deltas, s.deltas);
  const std::vector<std::uint8_t>* streams[kStreams] = {&s.ops, &s.ids, &positions, &deltas, &s.flags, &s.corners};
  for (auto* stream : streams) put_u64(payload, stream->size());
  for (auto* stream : streams) payload.insert(payload.end(), stream->begin(), stream->end());

  std::vector<std::uint8_t> out(kHeaderSize);
  std::memcpy(out.data(), kMagic, 4);
  out[4] = kVersion;
  hex_to_raw(base_sha256, out.data() + 5);
  hex_to_raw(result_sha256, out.data() + 37);
  for (int i = 0; i < 8; ++i) out[69 + i] = static_cast<std::uint8_t>(payload.size() >> (8 * i));
  auto count = static_cast<std::uint32_t>(edits.size());
  std::memcpy(out.data() + 77, &count, 4);
  std::size_t bound = ZSTD_compressBound(payload.size());
  out.resize(kHeaderSize + bound);
  // Corrections are small next to meshes: spend time on the ratio.
  int level = payload.size() < (64u << 20) ? 19 : 9;
  std::size_t written = ZSTD_compress(out.data() + kHeaderSize, bound, payload.data(), payload.size(), level);
  if (ZSTD_isError(written)) throw std::runtime_error("zstd compression of a correction failed");
  out.resize(kHeaderSize + written);
  return out;
}

CorrectionHeader read_correction_header(std::span<const std::uint8_t> bytes) {
  return parse(bytes).header;
}

EditList decode_correction(const mesh::Mesh& base, std::span<const std::uint8_t> bytes) {
  Parsed parsed = parse(bytes);
  EditMesh mesh(base);
  EditList edits;
  decode_into(parsed, mesh, &edits);
  return edits;
}

mesh::Mesh apply_correction(const mesh::Mesh& base, std::span<const std::uint8_t> bytes) {
  Parsed parsed = parse(bytes);
  std::string base_sha = mesh::mesh_sha256(base);
  if (base_sha != parsed.header.base_sha256)
    throw InvalidInput("correction applies to the mesh with SHA-256 " + parsed.header.base_sha256 +
                       ", not to this one (" + base_sha + ")");
  EditMesh mesh(base);
  decode_into(parsed, mesh, nullptr);
  mesh::Mesh result = mesh.compact();
  std::string result_sha = mesh::mesh_sha256(result);
  if (result_sha != parsed.header.result_sha256)
    throw InvalidInput("corrected mesh has SHA-256 " + result_sha + ", but the correction promises " +
                       parsed.header.result_sha256);
  return result;
}


}  // namespace meshflow::protocol
