// OFF reader, with the [ST][C][N][4][n]OFF variants: per-vertex extras (texture, colour, normal)
// and per-face colours after the indices are ignored; 4OFF divides by w.
#include <cmath>

#include "mesh/readers.h"

namespace meshflow::mesh {
namespace {

// The next line with content (comments after '#' removed); false at the end.
bool content_line(InputStream& in, std::string_view& line) {
  while (in.next_line(line)) {
    auto hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    std::string_view probe = line;
    if (!next_token(probe).empty()) return true;
  }
  return false;
}

}  // namespace

ReadInfo read_off(InputStream& in, MeshSink& sink) {
  ReadInfo info;
  info.format = Format::Off;
  std::string_view line;
  if (!content_line(in, line)) in.fail_line("empty file: expected an OFF header");
  std::string_view rest = line;
  std::string_view keyword = next_token(rest);
  // Prefix letters of the keyword: ST (texture), C (colour), N (normal), 4 (homogeneous),
  // n (dimension given next).
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF")
    in.fail_line("expected 'OFF' (or COFF, NOFF, STOFF, 4OFF...) as the header");
  std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  bool homogeneous = false;
  if (prefix.size() >= 2 && prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
  if (!prefix.empty() && prefix[0] == 'C') prefix.remove_prefix(1);
  if (!prefix.empty() && prefix[0] == 'N') prefix.remove_prefix(1);
  if (!prefix.empty() && prefix[0] == '4') homogeneous = true, prefix.remove_prefix(1);
  if (!prefix.empty() && prefix[0] == 'n') in.fail_line("nOFF (dimension other than 3) is not supported");
  if (!prefix.empty()) in.fail_line("unknown OFF variant '" + std::string(keyword) + "'");
  std::string_view peek = rest;
  if (next_token(peek) == "BINARY") in.fail_line("binary OFF is not supported");

  // The counts may follow the keyword on the same line.
  if (next_token(peek).empty() && !content_line(in, rest))
    in.fail_line("unexpected end of file: expected 'VERTICES FACES EDGES' counts");
  std::int64_t v_count = 0, f_count = 0;
  if (!parse_int(next_token(rest), v_count) || !parse_int(next_token(rest), f_count) ||
      v_count < 0 || f_count < 0)
    in.fail_line("expected 'VERTICES FACES EDGES' counts (non-negative integers)");
  if (v_count > 0xFFFFFFFEll) in.fail_line("more than 2^32-1 vertices");

  sink.begin(Format::Off, static_cast<std::int64_t>(plausible_count(in, v_count, 6)),
             static_cast<std::int64_t>(plausible_count(in, f_count, 8)));
  BatchWriter out(sink);
  for (std::int64_t i = 0; i < v_count; ++i) {
    if (!content_line(in, line))
      in.fail_line("unexpected end of file: expected " + std::to_string(v_count) +
                   " vertices, found " + std::to_string(i));
    double c[4] = {0, 0, 0, 1};
    int needed = homogeneous ? 4 : 3;
    for (int k = 0; k < needed; ++k) {
      std::string_view token = next_token(line);
      if (!parse_float(token, c[k]))
        in.fail_line("vertex " + std::to_string(i) + ": expected " + std::to_string(needed) +
                     " coordinates, found '" + std::string(token.substr(0, 20)) + "'");
    }
    if (homogeneous) {
      if (c[3] == 0) in.fail_line("vertex " + std::to_string(i) + ": homogeneous w is 0");
      for (int k = 0; k < 3; ++k) c[k] /= c[3];
    }
    Point p{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      in.fail_line("vertex " + std::to_string(i) + " has a coordinate that is not a finite float");
    out.vertex(p);
  }
  out.flush_vertices();
  info.raw_vertices = static_cast<std::uint64_t>(v_count);
  if (!sink.wants_triangles()) {
    sink.end();
    return info;
  }
  std::vector<Index> polygon;
  for (std::int64_t f = 0; f < f_count; ++f) {
    if (!content_line(in, line))
      in.fail_line("unexpected end of file: expected " + std::to_string(f_count) +
                   " faces, found " + std::to_string(f));
    std::int64_t n = 0;
    std::string_view token = next_token(line);
    if (!parse_int(token, n) || n < 0)
      in.fail_line("face " + std::to_string(f) + ": expected a vertex count, found '" +
                   std::string(token.substr(0, 20)) + "'");
    if (n < 3)
      in.fail_line("face " + std::to_string(f) + " has " + std::to_string(n) +
                   " vertices; expected at least 3");
    polygon.clear();
    for (std::int64_t k = 0; k < n; ++k) {
      std::int64_t index = 0;
      token = next_token(line);
      if (!parse_int(token, index))
        in.fail_line("face " + std::to_string(f) + ": expected " + std::to_string(n) +
                     " vertex indices, found '" + std::string(token.substr(0, 20)) + "'");
      if (index < 0 || index >= v_count)
        in.fail_line("face " + std::to_string(f) + ": vertex index " + std::to_string(index) +
                     " out of range (" + std::to_string(v_count) + " vertices)");
      polygon.push_back(static_cast<Index>(index));
    }
    // Anything after the indices is a face colour: ignored.
    info.faces_read++;
    if (n > 3) info.polygons++;
    out.polygon(polygon.data(), polygon.size());
  }
  out.flush();
  if (content_line(in, line))
    in.fail_line("unexpected data after the " + std::to_string(f_count) +
                 " faces the header declares (is the face count too small?)");
  sink.end();
  return info;
}

}  // namespace meshflow::mesh
