// OBJ reader: v (extra w or colour values ignored), vt/vn/vp and grouping/material statements
// skipped, faces `f a`, `f a/b`, `f a//c`, `f a/b/c` with negative (relative) indices,
// polygons fan-triangulated. A face may refer only to vertices defined before it.
#include <cmath>

#include "mesh/readers.h"

namespace meshflow::mesh {

ReadInfo read_obj(InputStream& in, MeshSink& sink) {
  ReadInfo info;
  info.format = Format::Obj;
  sink.begin(Format::Obj, -1, -1);
  BatchWriter out(sink);
  std::uint64_t vertex_count = 0;
  std::vector<Index> polygon;
  std::string_view line;
  bool any_statement = false;
  while (in.next_line(line)) {
    std::string_view rest = line;
    std::string_view keyword = next_token(rest);
    if (keyword.empty() || keyword[0] == '#') continue;
    any_statement = true;
    if (keyword == "v") {
      double c[3];
      for (int k = 0; k < 3; ++k) {
        std::string_view token = next_token(rest);
        if (!parse_float(token, c[k]))
          in.fail_line("vertex " + std::to_string(vertex_count + 1) +
                       ": expected 3 coordinates, found '" + std::string(token.substr(0, 20)) + "'");
      }
      for (std::string_view extra = next_token(rest); !extra.empty(); extra = next_token(rest)) {
        double ignored;
        if (!parse_float(extra, ignored))
          in.fail_line("vertex " + std::to_string(vertex_count + 1) + ": unexpected '" +
                       std::string(extra.substr(0, 20)) + "' after the coordinates");
      }
      Point p{static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
        in.fail_line("vertex " + std::to_string(vertex_count + 1) +
                     " has a coordinate that is not a finite float");
      if (vertex_count == 0xFFFFFFFEull) in.fail_line("more than 2^32-1 vertices");
      out.vertex(p);
      ++vertex_count;
    } else if (keyword == "f") {
      polygon.clear();
      for (std::string_view token = next_token(rest); !token.empty(); token = next_token(rest)) {
        std::string_view index_text = token.substr(0, token.find('/'));
        std::int64_t index = 0;
        if (!parse_int(index_text, index))
          in.fail_line("face: expected a vertex index, found '" + std::string(token.substr(0, 20)) + "'");
        std::int64_t resolved = index > 0 ? index - 1 : static_cast<std::int64_t>(vertex_count) + index;
        if (index == 0 || resolved < 0 || resolved >= static_cast<std::int64_t>(vertex_count))
          in.fail_line("face: vertex index " + std::to_string(index) + " out of range (" +
                       std::to_string(vertex_count) + " vertices defined so far; indices are 1-based)");
        polygon.push_back(static_cast<Index>(resolved));
      }
      if (polygon.size() < 3)
        in.fail_line("face has " + std::to_string(polygon.size()) + " vertices; expected at least 3");
      if (!sink.wants_triangles()) continue;
      // Triangles refer to vertices already handed out.
      out.flush_vertices();
      info.faces_read++;
      if (polygon.size() > 3) info.polygons++;
      out.polygon(polygon.data(), polygon.size());
    } else if (keyword == "vt" || keyword == "vn" || keyword == "vp" || keyword == "o" ||
               keyword == "g" || keyword == "s" || keyword == "usemtl" || keyword == "mtllib" ||
               keyword == "l" || keyword == "p" || keyword == "mg" || keyword == "lod" ||
               keyword == "cstype" || keyword == "deg" || keyword == "curv" ||
               keyword == "curv2" || keyword == "surf" || keyword == "parm" ||
               keyword == "end" || keyword == "bevel" || keyword == "c_interp" ||
               keyword == "d_interp" || keyword == "trace_obj" || keyword == "shadow_obj" ||
               keyword == "usemap" || keyword == "maplib") {
      continue;
    } else {
      in.fail_line("unknown OBJ statement '" + std::string(keyword.substr(0, 20)) + "'");
    }
  }
  if (!any_statement) in.fail_line("empty file: no OBJ statements");
  out.flush();
  info.raw_vertices = vertex_count;
  sink.end();
  return info;
}

}  // namespace meshflow::mesh
