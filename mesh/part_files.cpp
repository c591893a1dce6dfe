#include "mesh/part_files.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <unordered_set>

#include "mesh/errors.h"
#include "mesh/mesh_io.h"

namespace meshflow::mesh {
namespace {

constexpr char kMagic[8] = {'M', 'F', 'P', 'A', 'R', 'T', '2', '\n'};
constexpr char kRemMagic[8] = {'M', 'F', 'R', 'E', 'M', '0', '1', '\n'};

template <typename T>
void put(std::vector<std::uint8_t>& out, const T& value) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

class Cursor {
 public:
  Cursor(std::span<const std::uint8_t> bytes, const std::string& name) : bytes_(bytes), name_(name) {}
  template <typename T>
  T get(const char* what) {
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  void need(std::uint64_t n, const char* what) const {
    if (n > bytes_.size() - at_) fail(std::string("unexpected end of file: expected ") + what);
  }
  [[noreturn]] void fail(const std::string& reason) const { fail_at(at_, reason); }
  [[noreturn]] void fail_at(std::size_t offset, const std::string& reason) const {
    throw ParseError({.file = name_, .line = {}, .column = {}, .byte_offset = offset}, reason);
  }
  std::size_t offset() const { return at_; }
  std::size_t remaining() const { return bytes_.size() - at_; }

 private:
  std::span<const std::uint8_t> bytes_;
  std::string name_;
  std::size_t at_ = 0;
};

}  // namespace

std::vector<std::uint8_t> encode_part(const PartFile& part) {
  const bool quadrics = !part.quadrics.empty();
  std::vector<std::uint8_t> out;
  out.reserve(25 + part.positions.size() * (8 + 12 + 4 + (quadrics ? 88 : 0)) + part.triangles.size() * 12);
  out.assign(kMagic, kMagic + 8);
  put<std::uint64_t>(out, part.positions.size());
  put<std::uint64_t>(out, part.triangles.size());
  put<std::uint8_t>(out, quadrics);
  for (std::size_t v = 0; v < part.positions.size(); ++v) {
    put(out, part.global_ids[v]);
    for (float c : part.positions[v]) put(out, c);
    put<std::uint32_t>(out, part.partner[v]);
    if (quadrics)
      for (double q : part.quadrics[v]) put(out, q);
  }
  for (const Triangle& t : part.triangles)
    for (Index v : t) put(out, v);
  return out;
}

PartFile decode_part(std::span<const std::uint8_t> bytes, const std::string& name) {
  Cursor in(bytes, name);
  char magic[8];
  for (char& c : magic) c = static_cast<char>(in.get<std::uint8_t>("the part header"));
  if (std::memcmp(magic, kMagic, 6) == 0 && magic[6] == '1' && magic[7] == '\n')
    in.fail_at(0, "a part file of an older format (MFPART1): partition the mesh again");
  if (std::memcmp(magic, kMagic, 8) != 0) in.fail_at(0, "not a meshflow part file (expected \"MFPART2\")");
  auto vertices = in.get<std::uint64_t>("the vertex count");
  auto triangles = in.get<std::uint64_t>("the triangle count");
  auto has_quadrics = in.get<std::uint8_t>("the quadric flag");
  if (has_quadrics > 1) in.fail("quadric flag must be 0 or 1");
  // The encoder sets the flag exactly when there are quadrics, so an empty part never has it.
  if (has_quadrics && vertices == 0) in.fail("quadric flag set on a part without vertices");
  const std::uint64_t vertex_bytes = 8 + 12 + 4 + (has_quadrics ? 88 : 0);
  // Both counts must fit the bytes left before anything is allocated.
  if (vertices > in.remaining() / vertex_bytes || triangles > in.remaining() / 12 ||
      vertices * vertex_bytes + triangles * 12 != in.remaining())
    in.fail("counts (" + std::to_string(vertices) + " vertices, " + std::to_string(triangles) +
            " triangles) do not match the " + std::to_string(in.remaining()) + " bytes that follow");
  if (vertices > 0xffffffffu) in.fail("more than 2^32 vertices in one part");
  PartFile part;
  part.global_ids.resize(vertices);
  part.positions.resize(vertices);
  part.partner.resize(vertices);
  if (has_quadrics) part.quadrics.resize(vertices);
  for (std::uint64_t v = 0; v < vertices; ++v) {
    part.global_ids[v] = in.get<std::uint64_t>("a global vertex id");
    if (v > 0 && part.global_ids[v] <= part.global_ids[v - 1]) in.fail("global vertex ids must ascend");
    for (float& c : part.positions[v]) c = in.get<float>("a coordinate");
    part.partner[v] = in.get<std::uint32_t>("a partner part");
    if (part.partner[v] >= kMaxParts && part.partner[v] != kNotShared && part.partner[v] != kSharedBy3)
      in.fail("partner " + std::to_string(part.partner[v]) + " is neither a part (< 2^24) nor a shared flag");
    if (has_quadrics)
      for (double& q : part.quadrics[v]) q = in.get<double>("a quadric");
  }
  part.triangles.resize(triangles);
  for (Triangle& t : part.triangles)
    for (Index& v : t) {
      v = in.get<Index>("a triangle corner");
      if (v >= vertices) in.fail("triangle corner " + std::to_string(v) + " >= " + std::to_string(vertices) + " vertices");
    }
  return part;
}

void write_part(const PartFile& part, const std::string& path) {
  std::vector<std::uint8_t> bytes = encode_part(part);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw IoError(path + ": cannot write the part file");
}

std::vector<std::pair<std::uint32_t, PartFile>> seam_sides(const PartFile& part) {
  // The triangles of each seam, in one pass (a triangle may touch up to three).
  std::vector<std::uint32_t> partners;
  std::vector<std::vector<std::size_t>> triangles;
  auto slot = [&](std::uint32_t q) {
    auto it = std::lower_bound(partners.begin(), partners.end(), q);
    const std::size_t at = it - partners.begin();
    if (it == partners.end() || *it != q) {
      partners.insert(it, q);
      triangles.insert(triangles.begin() + at, std::vector<std::size_t>());
    }
    return at;
  };
  for (std::size_t t = 0; t < part.triangles.size(); ++t) {
    const Triangle& tri = part.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t q = part.partner[tri[k]];
      if (q >= kSharedBy3) continue;
      if ((k > 0 && part.partner[tri[0]] == q) || (k > 1 && part.partner[tri[1]] == q)) continue;  // once per triangle
      triangles[slot(q)].push_back(t);
    }
  }
  std::vector<std::pair<std::uint32_t, PartFile>> sides;
  constexpr Index kUnused = ~Index{0};
  std::vector<Index> renumber(part.positions.size(), kUnused);
  for (std::size_t i = 0; i < partners.size(); ++i) {
    std::vector<Index> used;
    for (std::size_t t : triangles[i])
      for (Index v : part.triangles[t])
        if (renumber[v] == kUnused) renumber[v] = 0, used.push_back(v);
    std::sort(used.begin(), used.end());  // this part's order: global ids ascend
    PartFile side;
    for (Index v : used) {
      renumber[v] = static_cast<Index>(side.positions.size());
      side.global_ids.push_back(part.global_ids[v]);
      side.positions.push_back(part.positions[v]);
      side.partner.push_back(part.partner[v]);
    }
    for (std::size_t t : triangles[i]) {
      const Triangle& tri = part.triangles[t];
      side.triangles.push_back({renumber[tri[0]], renumber[tri[1]], renumber[tri[2]]});
    }
    for (Index v : used) renumber[v] = kUnused;
    sides.emplace_back(partners[i], std::move(side));
  }
  return sides;
}

PartFile read_part(const std::string& path) {
  return decode_part(read_file_bytes(path), path);
}

std::vector<std::uint8_t> encode_rem(const RemFile& rem) {
  std::vector<std::uint8_t> out(kRemMagic, kRemMagic + 8);
  out.reserve(24 + 16 * rem.merges.size());
  put(out, rem.from);
  put(out, rem.to);
  put<std::uint64_t>(out, rem.merges.size());
  for (const auto& [removed, kept] : rem.merges) put(out, removed), put(out, kept);
  return out;
}

RemFile decode_rem(std::span<const std::uint8_t> bytes, const std::string& name) {
  Cursor in(bytes, name);
  char magic[8];
  for (char& c : magic) c = static_cast<char>(in.get<std::uint8_t>("the Rem file header"));
  if (std::memcmp(magic, kRemMagic, 8) != 0) in.fail_at(0, "not a meshflow Rem file (expected \"MFREM01\")");
  RemFile rem;
  rem.from = in.get<std::uint32_t>("the part it comes from");
  rem.to = in.get<std::uint32_t>("the part it goes to");
  if (rem.from >= kMaxParts || rem.to >= kMaxParts || rem.from == rem.to)
    in.fail_at(8, "parts " + std::to_string(rem.from) + " -> " + std::to_string(rem.to) + " are not two parts (< 2^24)");
  const auto count = in.get<std::uint64_t>("the merge count");
  if (count > in.remaining() / 16 || count * 16 != in.remaining())
    in.fail("count (" + std::to_string(count) + " merges) does not match the " + std::to_string(in.remaining()) +
            " bytes that follow");
  rem.merges.resize(count);
  std::unordered_set<std::uint64_t> removed;
  removed.reserve(count);
  for (auto& [gone, kept] : rem.merges) {
    const std::size_t at = in.offset();
    gone = in.get<std::uint64_t>("a removed vertex");
    kept = in.get<std::uint64_t>("a kept vertex");
    if (gone == kept) in.fail_at(at, "vertex " + std::to_string(gone) + " merged into itself");
    if (removed.count(kept)) in.fail_at(at, "vertex " + std::to_string(kept) + " kept after it was removed");
    if (!removed.insert(gone).second) in.fail_at(at, "vertex " + std::to_string(gone) + " removed twice");
  }
  return rem;
}

void write_rem(const RemFile& rem, const std::string& path) {
  std::vector<std::uint8_t> bytes = encode_rem(rem);
  {
    std::ofstream out(path + ".tmp", std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError(path + ": cannot write the Rem file");
  }
  std::filesystem::rename(path + ".tmp", path);
}

RemFile read_rem(const std::string& path) { return decode_rem(read_file_bytes(path), path); }

std::string encode_parts_index(const PartsIndex& index) {
  std::ostringstream out;
  out.precision(17);  // the diagonal round-trips exactly, whatever the mesh's scale
  out << "parts " << index.parts << "\ndiagonal " << index.diagonal << "\n";
  for (std::size_t p = 0; p < index.adjacency.size(); ++p) {
    out << "neighbours " << p;
    for (auto q : index.adjacency[p]) out << ' ' << q;
    out << '\n';
  }
  return out.str();
}

PartsIndex decode_parts_index(std::string_view text, const std::string& name) {
  PartsIndex index;
  std::size_t line_no = 0, at = 0;
  auto fail = [&](const std::string& reason) {
    throw ParseError({.file = name, .line = line_no, .column = {}, .byte_offset = {}}, reason);
  };
  auto next_line = [&](std::string& line) {
    if (at >= text.size()) return false;
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    line.assign(text.substr(at, end - at));
    at = end + 1;
    ++line_no;
    return true;
  };
  std::string line, key, extra;
  if (!next_line(line)) fail("expected \"parts N\"");
  {
    std::istringstream words(line);
    long long n = -1;
    if (!(words >> key >> n) || key != "parts" || n < 0 || n > (1 << 24) || (words >> extra)) fail("expected \"parts N\" (N < 2^24)");
    index.parts = static_cast<std::size_t>(n);
    if (index.parts > text.size() / 12) fail("more parts than neighbour lines can follow");
  }
  if (!next_line(line)) fail("expected \"diagonal X\"");
  {
    std::istringstream words(line);
    if (!(words >> key >> index.diagonal) || key != "diagonal" || !(index.diagonal >= 0) || index.diagonal > 1e300 ||
        (words >> extra))
      fail("expected \"diagonal X\" (X >= 0)");
  }
  index.adjacency.assign(index.parts, {});
  for (std::size_t p = 0; p < index.parts; ++p) {
    if (!next_line(line)) fail("expected \"neighbours " + std::to_string(p) + " ...\"");
    std::istringstream words(line);
    long long got = -1, q;
    if (!(words >> key >> got) || key != "neighbours" || got != static_cast<long long>(p))
      fail("expected \"neighbours " + std::to_string(p) + " ...\"");
    while (words >> q) {
      if (q < 0 || q >= static_cast<long long>(index.parts) || q == got) fail("neighbour " + std::to_string(q) + " is not another part");
      if (!index.adjacency[p].empty() && q <= index.adjacency[p].back()) fail("neighbours must ascend");
      index.adjacency[p].push_back(static_cast<std::uint32_t>(q));
    }
    if (!words.eof()) fail("expected part numbers");
  }
  if (next_line(line)) fail("unexpected text after the last part");
  return index;
}

}  // namespace meshflow::mesh
