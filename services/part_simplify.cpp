#include "services/part_simplify.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "mesh/errors.h"
#include "services/simplify.h"

namespace meshflow::services {

std::string PartStats::to_json() const {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "{\"vertices_in\": %zu, \"triangles_in\": %zu, \"vertices_out\": %zu, \"triangles_out\": %zu, "
                "\"shared\": %zu, \"max_rms_error\": %.9g, \"seconds\": %.3f}",
                vertices_in, triangles_in, vertices_out, triangles_out, shared, max_rms_error, seconds);
  return buf;
}

mesh::PartFile simplify_part(const mesh::PartFile& part, double max_error_abs, PartStats* stats) {
  if (!(max_error_abs > 0)) throw InvalidInput("the part's max error must be > 0");
  auto start = std::chrono::steady_clock::now();
  mesh::Mesh m{part.positions, part.triangles};
  std::vector<bool> locked(part.shared.begin(), part.shared.end());
  SimplifyParams sp;
  sp.max_error = max_error_abs;
  sp.locked = &locked;
  sp.export_quadrics = true;
  SimplifyResult r = simplify(m, sp);
  mesh::PartFile out;
  for (mesh::Index i : r.source_ids) {
    out.global_ids.push_back(part.global_ids[i]);
    out.shared.push_back(part.shared[i]);
  }
  out.positions = std::move(r.output.positions);
  out.triangles = std::move(r.output.triangles);
  out.quadrics = std::move(r.quadrics);
  if (stats) {
    stats->vertices_in = part.positions.size(), stats->triangles_in = part.triangles.size();
    stats->vertices_out = out.positions.size(), stats->triangles_out = out.triangles.size();
    stats->shared = 0;
    for (auto s : part.shared) stats->shared += s;
    stats->max_rms_error = r.max_rms_error;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return out;
}

PartStats simplify_part_file(const std::string& in, const std::string& out, double max_error_abs) {
  PartStats stats;
  mesh::PartFile simplified = simplify_part(mesh::read_part(in), max_error_abs, &stats);
  mesh::write_part(simplified, out + ".tmp");
  std::filesystem::rename(out + ".tmp", out);
  return stats;
}

}  // namespace meshflow::services
