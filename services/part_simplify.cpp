#include "services/part_simplify.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "mesh/errors.h"
#include "services/simplify.h"

namespace meshflow::services {

std::string PartStats::to_json() const {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "{\"vertices_in\": %zu, \"triangles_in\": %zu, \"vertices_out\": %zu, \"triangles_out\": %zu, "
                "\"shared\": %zu, \"replayed\": %zu, \"seam_removed\": %zu, \"max_rms_error\": %.9g, \"seconds\": %.3f}",
                vertices_in, triangles_in, vertices_out, triangles_out, shared, replayed, seam_removed, max_rms_error, seconds);
  return buf;
}

namespace {

// Local id of a global id (the part's ids ascend), or npos.
std::size_t local_of(const mesh::PartFile& part, std::uint64_t gid) {
  auto it = std::lower_bound(part.global_ids.begin(), part.global_ids.end(), gid);
  return it != part.global_ids.end() && *it == gid ? std::size_t(it - part.global_ids.begin()) : std::size_t(-1);
}

// The neighbours' merges (removed -> kept, through chains) as each vertex's final target, for
// SimplifyParams::merged_into. Returns the number of vertices removed.
std::size_t replay(const mesh::PartFile& part, const PartSeams& seams, std::vector<mesh::Index>& root) {
  const std::size_t V = part.positions.size();
  root.resize(V);
  for (std::size_t v = 0; v < V; ++v) root[v] = static_cast<mesh::Index>(v);
  auto find = [&](mesh::Index v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  std::size_t removed = 0;
  for (const mesh::RemFile& rem : seams.incoming) {
    const std::string from = "Rem file " + std::to_string(rem.from) + " -> " + std::to_string(rem.to) + ": ";
    if (rem.to != seams.part) throw InvalidInput(from + "not for part " + std::to_string(seams.part));
    for (const auto& [gone, kept] : rem.merges) {
      const std::size_t g = local_of(part, gone), k = local_of(part, kept);
      for (auto [gid, local] : {std::pair{gone, g}, std::pair{kept, k}})
        if (local == std::size_t(-1) || part.partner[local] != rem.from)
          throw InvalidInput(from + "vertex " + std::to_string(gid) + " is not shared by these two parts alone");
      const mesh::Index rg = find(static_cast<mesh::Index>(g)), rk = find(static_cast<mesh::Index>(k));
      if (rg == rk) throw InvalidInput(from + "vertex " + std::to_string(gone) + " merged twice");
      root[rg] = rk;
      ++removed;
    }
  }
  for (std::size_t v = 0; v < V; ++v) root[v] = find(static_cast<mesh::Index>(v));
  return removed;
}

}  // namespace

mesh::PartFile simplify_part(const mesh::PartFile& part, double max_error_abs, PartStats* stats, const PartSeams* seams,
                             std::vector<mesh::RemFile>* outgoing) {
  if (!(max_error_abs > 0)) throw InvalidInput("the part's max error must be > 0");
  auto start = std::chrono::steady_clock::now();
  const std::size_t V = part.positions.size();
  mesh::Mesh m{part.positions, part.triangles};
  std::vector<bool> locked(V, false);
  for (std::size_t v = 0; v < V; ++v) locked[v] = part.shared(v);
  std::vector<std::uint32_t> seam_partner;
  std::vector<mesh::Index> merged_into;
  std::size_t replayed = 0;
  SimplifyParams sp;
  if (seams) {
    replayed = replay(part, *seams, merged_into);
    if (replayed) sp.merged_into = &merged_into;
    // Free to go by half-edge collapses: the vertices shared with one unsimplified neighbour.
    seam_partner.assign(V, kNoPartner);
    for (std::size_t v = 0; v < V; ++v)
      if (part.shared(v) && std::find(seams->unsimplified.begin(), seams->unsimplified.end(), part.partner[v]) !=
                                seams->unsimplified.end()) {
        seam_partner[v] = part.partner[v];
        locked[v] = false;
      }
    sp.seam_partner = &seam_partner;
  }
  sp.max_error = max_error_abs;
  sp.locked = &locked;
  sp.export_quadrics = true;
  SimplifyResult r = simplify(m, sp);
  mesh::PartFile out;
  for (mesh::Index i : r.source_ids) {
    out.global_ids.push_back(part.global_ids[i]);
    out.partner.push_back(part.partner[i]);
  }
  out.positions = std::move(r.output.positions);
  out.triangles = std::move(r.output.triangles);
  out.quadrics = std::move(r.quadrics);
  if (seams && outgoing) {
    outgoing->clear();
    for (std::uint32_t q : seams->unsimplified) outgoing->push_back({seams->part, q, {}});
    for (auto [gone, kept] : r.seam_collapses) {
      auto it = std::find(seams->unsimplified.begin(), seams->unsimplified.end(), seam_partner[gone]);
      (*outgoing)[it - seams->unsimplified.begin()].merges.emplace_back(part.global_ids[gone], part.global_ids[kept]);
    }
  }
  if (stats) {
    stats->vertices_in = part.positions.size(), stats->triangles_in = part.triangles.size();
    stats->vertices_out = out.positions.size(), stats->triangles_out = out.triangles.size();
    stats->shared = 0;
    for (std::size_t v = 0; v < V; ++v) stats->shared += part.shared(v);
    stats->replayed = replayed;
    stats->seam_removed = r.seam_collapses.size();
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
