#include "services/part_simplify.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <unordered_map>
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

using Vec = std::array<double, 3>;

// The partner's side of this part's seam with it: the partner's triangles at the vertices the
// two share, in this part's vertex ids (the partner's own vertices numbered from V on), kept up
// to date with the half-edge collapses made here, as the partner will replay them.
class PartnerSide {
 public:
  PartnerSide(const mesh::PartFile& part, std::uint32_t self, const mesh::PartFile& partner) : positions_(part.positions) {
    const std::size_t V = part.positions.size();
    std::vector<mesh::Index> id(partner.positions.size());
    for (std::size_t v = 0; v < id.size(); ++v) {
      const std::size_t here = local_of(part, partner.global_ids[v]);
      id[v] = static_cast<mesh::Index>(here != std::size_t(-1) ? here : V + v);
      if (here == std::size_t(-1)) foreign_[id[v]] = partner.positions[v];
    }
    for (const mesh::Triangle& t : partner.triangles) {
      if (partner.partner[t[0]] != self && partner.partner[t[1]] != self && partner.partner[t[2]] != self) continue;
      const auto n = static_cast<std::uint32_t>(tris_.size());
      tris_.push_back({id[t[0]], id[t[1]], id[t[2]]});
      for (mesh::Index v : tris_.back()) fan_[v].push_back(n);
    }
    alive_.assign(tris_.size(), 1);
  }

  bool allows(mesh::Index drop, mesh::Index keep, mesh::Index apex, const std::vector<mesh::Index>& nk,
              const std::vector<mesh::Index>& nd) {
    // The partner's one triangle on the edge, and its apex.
    mesh::Index other_apex = 0;
    int on_edge = 0;
    for (std::uint32_t t : fan(drop))
      if (contains(tris_[t], keep)) {
        ++on_edge;
        for (mesh::Index v : tris_[t])
          if (v != keep && v != drop) other_apex = v;
      }
    if (on_edge != 1 || other_apex == apex) return false;
    // Link condition on the whole surface: the ends' only common neighbours are the two apexes.
    neighbours(keep, nk, around_keep_);
    neighbours(drop, nd, around_drop_);
    common_.clear();
    std::set_intersection(around_keep_.begin(), around_keep_.end(), around_drop_.begin(), around_drop_.end(),
                          std::back_inserter(common_));
    for (mesh::Index v : common_)
      if (v != apex && v != other_apex && v != keep && v != drop) return false;
    // No partner triangle flips when `drop` goes to `keep`'s place.
    const Vec to = at(keep);
    for (std::uint32_t t : fan(drop)) {
      const mesh::Triangle& tri = tris_[t];
      if (contains(tri, keep)) continue;
      Vec p[3], q[3];
      for (int k = 0; k < 3; ++k) p[k] = at(tri[k]), q[k] = tri[k] == drop ? to : p[k];
      const Vec before = cross(sub(p[1], p[0]), sub(p[2], p[0])), after = cross(sub(q[1], q[0]), sub(q[2], q[0]));
      const double lb = dot(before, before), la = dot(after, after);
      if (la <= 1e-12 * lb || la == 0 || dot(before, after) <= 0.2 * std::sqrt(lb * la)) return false;
    }
    return true;
  }

  void collapsed(mesh::Index drop, mesh::Index keep) {
    std::vector<std::uint32_t> moved = std::move(fan_[drop]);
    fan_.erase(drop);
    for (std::uint32_t t : moved) {
      if (!alive_[t]) continue;
      mesh::Triangle& tri = tris_[t];
      if (contains(tri, keep)) {
        alive_[t] = 0;
        for (mesh::Index v : tri)
          if (v != drop) std::erase(fan_[v], t);
      } else {
        for (mesh::Index& v : tri)
          if (v == drop) v = keep;
        fan_[keep].push_back(t);
      }
    }
  }

 private:
  static bool contains(const mesh::Triangle& t, mesh::Index v) { return t[0] == v || t[1] == v || t[2] == v; }
  static Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
  static Vec cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  }
  static double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  Vec at(mesh::Index v) const {
    const mesh::Point& p = v < positions_.size() ? positions_[v] : foreign_.at(v);
    return {p[0], p[1], p[2]};
  }
  const std::vector<std::uint32_t>& fan(mesh::Index v) const {
    static const std::vector<std::uint32_t> none;
    auto it = fan_.find(v);
    return it == fan_.end() ? none : it->second;
  }
  // v's neighbours on both sides: `here` (sorted) and the partner's.
  void neighbours(mesh::Index v, const std::vector<mesh::Index>& here, std::vector<mesh::Index>& out) const {
    out = here;
    for (std::uint32_t t : fan(v))
      if (alive_[t])
        for (mesh::Index w : tris_[t])
          if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  const std::vector<mesh::Point>& positions_;  // this part's; seam vertices never move here
  std::unordered_map<mesh::Index, mesh::Point> foreign_;
  std::vector<mesh::Triangle> tris_;
  std::vector<std::uint8_t> alive_;
  std::unordered_map<mesh::Index, std::vector<std::uint32_t>> fan_;
  std::vector<mesh::Index> around_keep_, around_drop_, common_;
};

// Routes each seam collapse to the side of the drop vertex's partner.
class PartnerSides : public SeamSide {
 public:
  PartnerSides(const mesh::PartFile& part, const PartSeams& seams, const std::vector<std::uint32_t>& partner)
      : seams_(seams), partner_(partner) {
    for (std::size_t i = 0; i < seams.unsimplified_parts.size(); ++i)
      sides_.emplace_back(part, seams.part, seams.unsimplified_parts[i]);
  }
  bool allows(mesh::Index drop, mesh::Index keep, mesh::Index apex, const std::vector<mesh::Index>& nk,
              const std::vector<mesh::Index>& nd) override {
    return side(drop).allows(drop, keep, apex, nk, nd);
  }
  void collapsed(mesh::Index drop, mesh::Index keep) override { side(drop).collapsed(drop, keep); }

 private:
  PartnerSide& side(mesh::Index drop) {
    auto it = std::find(seams_.unsimplified.begin(), seams_.unsimplified.end(), partner_[drop]);
    return sides_[it - seams_.unsimplified.begin()];
  }
  const PartSeams& seams_;
  const std::vector<std::uint32_t>& partner_;
  std::vector<PartnerSide> sides_;
};

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
  std::unique_ptr<PartnerSides> sides;
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
    if (!seams->unsimplified_parts.empty()) {
      if (seams->unsimplified_parts.size() != seams->unsimplified.size())
        throw InvalidInput("one part file per unsimplified neighbour is needed");
      sides = std::make_unique<PartnerSides>(part, *seams, seam_partner);
      sp.seam_side = sides.get();
    }
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
