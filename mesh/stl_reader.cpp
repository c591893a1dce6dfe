// STL reader, ascii and binary (several `solid` blocks allowed in ascii). Corners are welded
// exactly: the same float32 values (with -0 = +0) become one vertex, numbered in order of first
// appearance.
#include <bit>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "mesh/readers.h"

namespace meshflow::mesh {
namespace {

struct PointKey {
  std::uint32_t bits[3];
  bool operator==(const PointKey& o) const {
    return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
  }
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = k.bits[0] * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + k.bits[1] * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + k.bits[2] * 0x94D049BB133111EBull;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};

class Welder {
 public:
  explicit Welder(BatchWriter& out) : out_(out) {}
  Index add(Point p) {
    for (float& c : p)
      if (c == 0.0f) c = 0.0f;  // -0 -> +0
    PointKey key{{std::bit_cast<std::uint32_t>(p[0]), std::bit_cast<std::uint32_t>(p[1]),
                  std::bit_cast<std::uint32_t>(p[2])}};
    auto [it, inserted] = index_.try_emplace(key, static_cast<Index>(index_.size()));
    if (inserted) out_.vertex(p);
    return it->second;
  }
  std::size_t size() const { return index_.size(); }

 private:
  BatchWriter& out_;
  std::unordered_map<PointKey, Index, PointKeyHash> index_;
};

void check_finite(InputStream& in, const Point& p, std::uint64_t facet, bool ascii,
                  std::uint64_t byte) {
  if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) return;
  std::string reason = "facet " + std::to_string(facet) + " has a vertex coordinate that is not finite";
  if (ascii) in.fail_line(reason);
  in.fail_byte(reason, byte);
}

ReadInfo read_binary(InputStream& in, MeshSink& sink) {
  ReadInfo info;
  info.format = Format::Stl;
  info.is_binary = true;
  char header[84];
  in.read_exact(header, 84, "the binary STL header");
  std::uint32_t count;
  std::memcpy(&count, header + 80, 4);
  std::uint64_t expected = 84 + 50ull * count;
  if (in.known_size() >= 0 && static_cast<std::uint64_t>(in.known_size()) != expected)
    in.fail_byte("binary STL header says " + std::to_string(count) + " triangles (" +
                     std::to_string(expected) + " bytes) but the file has " +
                     std::to_string(in.known_size()) + " bytes",
                 80);
  sink.begin(Format::Stl, -1, static_cast<std::int64_t>(plausible_count(in, count, 50)));
  BatchWriter out(sink);
  Welder welder(out);
  for (std::uint32_t f = 0; f < count; ++f) {
    std::uint64_t byte = in.offset();
    if (in.fill(50) < 50)
      in.fail_byte("unexpected end of file in facet " + std::to_string(f) + " of " +
                       std::to_string(count) + ": expected 50 more bytes",
                   byte);
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      Point p;
      std::memcpy(p.data(), in.data() + 12 + 12 * k, 12);
      check_finite(in, p, f, false, byte);
      t[k] = welder.add(p);
    }
    in.skip(50);
    out.flush_vertices();
    out.triangle(t);
  }
  if (!in.at_end())
    in.fail_byte("unexpected data after the " + std::to_string(count) + " facets the header declares",
                 in.offset());
  out.flush();
  info.faces_read = count;
  info.raw_vertices = 3ull * count;
  sink.end();
  return info;
}

ReadInfo read_ascii(InputStream& in, MeshSink& sink) {
  ReadInfo info;
  info.format = Format::Stl;
  sink.begin(Format::Stl, -1, -1);
  BatchWriter out(sink);
  Welder welder(out);
  std::string_view line;
  enum { Outside, InSolid, InFacet, InLoop } state = Outside;
  Triangle t{};
  int corners = 0;
  std::uint64_t facets = 0;
  auto expect = [&](bool ok, const char* what) {
    if (!ok) in.fail_line(std::string("expected ") + what);
  };
  while (in.next_line(line)) {
    std::string_view rest = line;
    std::string_view keyword = next_token(rest);
    if (keyword.empty()) continue;
    switch (state) {
      case Outside:
        expect(keyword == "solid", "'solid'");
        state = InSolid;
        break;
      case InSolid:
        if (keyword == "endsolid") {
          state = Outside;
        } else {
          expect(keyword == "facet", "'facet' or 'endsolid'");
          state = InFacet;
        }
        break;
      case InFacet:
        if (keyword == "outer") {
          expect(next_token(rest) == "loop", "'outer loop'");
          state = InLoop;
          corners = 0;
        } else {
          expect(keyword == "endfacet", "'outer loop' or 'endfacet'");
          expect(corners == 3, "3 vertices in the facet");
          out.flush_vertices();
          out.triangle(t);
          ++facets;
          corners = 0;
          state = InSolid;
        }
        break;
      case InLoop:
        if (keyword == "vertex") {
          expect(corners < 3, "'endloop' after 3 vertices");
          double c[3];
          for (double& v : c) {
            std::string_view token = next_token(rest);
            if (!parse_float(token, v))
              in.fail_line("facet " + std::to_string(facets) + ": expected 3 coordinates after 'vertex', found '" +
                           std::string(token.substr(0, 20)) + "'");
          }
          Point p{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
          check_finite(in, p, facets, true, 0);
          t[corners++] = welder.add(p);
        } else {
          expect(keyword == "endloop", "'vertex' or 'endloop'");
          expect(corners == 3, "3 vertices before 'endloop'");
          state = InFacet;
          corners = 3;
        }
        break;
    }
  }
  if (state != Outside && !(state == InSolid && facets > 0))
    in.fail_line("unexpected end of file inside a solid");
  if (facets == 0 && in.line() <= 1) in.fail_line("empty STL: no facets");
  out.flush();
  info.faces_read = facets;
  info.raw_vertices = 3 * facets;
  sink.end();
  return info;
}

}  // namespace

ReadInfo read_stl(InputStream& in, MeshSink& sink) {
  std::size_t n = in.fill(512);
  std::string_view head(in.data(), n);
  bool starts_solid = head.size() >= 5 && head.substr(0, 5) == "solid";
  bool binary_size_matches = false;
  if (in.known_size() >= 84 && n >= 84) {
    std::uint32_t count;
    std::memcpy(&count, in.data() + 80, 4);
    binary_size_matches = static_cast<std::uint64_t>(in.known_size()) == 84 + 50ull * count;
  }
  bool ascii = starts_solid && !binary_size_matches &&
               (head.find("facet") != std::string_view::npos ||
                head.find("endsolid") != std::string_view::npos);
  return ascii ? read_ascii(in, sink) : read_binary(in, sink);
}

}  // namespace meshflow::mesh
