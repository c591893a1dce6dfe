#include "services/simplify.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "mesh/errors.h"

namespace meshflow::services {
namespace {

using mesh::Index;
using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Symmetric 4x4 quadric of plane distances, plus the total weight (area) behind it.
struct Quadric {
  double a2 = 0, ab = 0, ac = 0, ad = 0, b2 = 0, bc = 0, bd = 0, c2 = 0, cd = 0, d2 = 0, weight = 0;
  void add_plane(const Vec& n, double d, double w) {
    a2 += w * n[0] * n[0], ab += w * n[0] * n[1], ac += w * n[0] * n[2], ad += w * n[0] * d;
    b2 += w * n[1] * n[1], bc += w * n[1] * n[2], bd += w * n[1] * d;
    c2 += w * n[2] * n[2], cd += w * n[2] * d, d2 += w * d * d;
  }
  Quadric& operator+=(const Quadric& o) {
    a2 += o.a2, ab += o.ab, ac += o.ac, ad += o.ad, b2 += o.b2, bc += o.bc, bd += o.bd;
    c2 += o.c2, cd += o.cd, d2 += o.d2, weight += o.weight;
    return *this;
  }
  double eval(const Vec& v) const {
    double x = v[0], y = v[1], z = v[2];
    double e = a2 * x * x + 2 * ab * x * y + 2 * ac * x * z + 2 * ad * x + b2 * y * y + 2 * bc * y * z +
               2 * bd * y + c2 * z * z + 2 * cd * z + d2;
    return std::max(0.0, e);
  }
  // The minimiser, when the 3x3 system is well conditioned.
  bool optimum(Vec& out) const {
    double det = a2 * (b2 * c2 - bc * bc) - ab * (ab * c2 - bc * ac) + ac * (ab * bc - b2 * ac);
    double scale = std::max({std::abs(a2), std::abs(b2), std::abs(c2), 1e-300});
    if (std::abs(det) < 1e-10 * scale * scale * scale) return false;
    double inv = 1.0 / det;
    double m00 = (b2 * c2 - bc * bc) * inv, m01 = (ac * bc - ab * c2) * inv, m02 = (ab * bc - ac * b2) * inv;
    double m11 = (a2 * c2 - ac * ac) * inv, m12 = (ab * ac - a2 * bc) * inv, m22 = (a2 * b2 - ab * ab) * inv;
    out = {-(m00 * ad + m01 * bd + m02 * cd), -(m01 * ad + m11 * bd + m12 * cd), -(m02 * ad + m12 * bd + m22 * cd)};
    return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
  }
};

constexpr double kBoundaryWeight = 100.0;

class Simplifier {
 public:
  Simplifier(const mesh::Mesh& input, const SimplifyParams& params) : params_(params) {
    std::size_t V = input.positions.size();
    pos_.resize(V);
    for (std::size_t v = 0; v < V; ++v)
      pos_[v] = {input.positions[v][0], input.positions[v][1], input.positions[v][2]};
    tris_ = input.triangles;
    tri_alive_.assign(tris_.size(), true);
    vt_.resize(V);
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& tri = tris_[t];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
        // Degenerate by index: kept as is, its vertices locked.
        for (Index v : tri) locked_.push_back(v);
        continue;
      }
      for (Index v : tri) vt_[v].push_back(static_cast<Index>(t));
    }
    quadric_.resize(V);
    boundary_.assign(V, false);
    std::vector<bool> lock(V, false);
    for (Index v : locked_) lock[v] = true;
    lock_ = std::move(lock);
    if (params_.locked)
      for (std::size_t v = 0; v < V && v < params_.locked->size(); ++v)
        if ((*params_.locked)[v]) lock_[v] = true;
    stamp_.assign(V, 0);
    alive_.assign(V, false);
    for (std::size_t v = 0; v < V; ++v) alive_[v] = !vt_[v].empty();
    if (params_.quadrics) {
      for (std::size_t v = 0; v < V && v < params_.quadrics->size(); ++v) quadric_[v] = from_array((*params_.quadrics)[v]);
    } else for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& tri = tris_[t];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      Vec n = cross(sub(pos_[tri[1]], pos_[tri[0]]), sub(pos_[tri[2]], pos_[tri[0]]));
      double len = std::sqrt(dot(n, n));
      if (len == 0) continue;
      Vec u{n[0] / len, n[1] / len, n[2] / len};
      double area = 0.5 * len;
      Quadric q;
      q.add_plane(u, -dot(u, pos_[tri[0]]), area);
      q.weight = area;
      for (Index v : tri) quadric_[v] += q;
    }
    classify_edges();
    live_vertices_ = static_cast<std::size_t>(std::count(alive_.begin(), alive_.end(), true));
  }

  SimplifyResult run() {
    for (std::size_t v = 0; v < pos_.size(); ++v)
      if (alive_[v]) push_edges_of(static_cast<Index>(v));
    SimplifyResult result;
    std::size_t start_vertices = live_vertices_;
    while (!heap_.empty()) {
      if (params_.target_vertices && live_vertices_ <= params_.target_vertices) break;
      Candidate c = heap_.top();
      heap_.pop();
      if (!alive_[c.keep] || !alive_[c.drop] || stamp_[c.keep] != c.keep_stamp || stamp_[c.drop] != c.drop_stamp)
        continue;
      if (params_.max_error > 0 && c.rms > params_.max_error) break;
      if (!collapse(c)) continue;
      result.collapses++;
      result.max_rms_error = std::max(result.max_rms_error, c.rms);
      if ((result.collapses & 0x3fff) == 0) {
        if (params_.cancel && params_.cancel->load()) throw std::runtime_error("cancelled");
        if (params_.progress && start_vertices > 0)
          params_.progress(double(start_vertices - live_vertices_) / double(start_vertices));
      }
    }
    result.output = output(result);
    return result;
  }

 private:
  struct Candidate {
    double cost, rms;
    Index keep, drop;
    std::uint32_t keep_stamp, drop_stamp;
    Vec position;
    bool operator<(const Candidate& o) const { return cost > o.cost; }  // min-heap
  };

  void classify_edges() {
    std::vector<std::uint64_t> keys;
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& tri = tris_[t];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      for (int k = 0; k < 3; ++k) {
        Index a = tri[k], b = tri[(k + 1) % 3];
        keys.push_back(static_cast<std::uint64_t>(std::min(a, b)) << 32 | std::max(a, b));
      }
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 0; i < keys.size();) {
      std::size_t j = i;
      while (j < keys.size() && keys[j] == keys[i]) ++j;
      Index a = static_cast<Index>(keys[i] >> 32), b = static_cast<Index>(keys[i] & 0xffffffff);
      if (j - i == 1) {
        boundary_[a] = boundary_[b] = true;
        if (wants_boundary_plane(a, b)) add_boundary_plane(a, b);
      } else if (j - i > 2) {
        lock_[a] = lock_[b] = true;  // non-manifold edge
      }
      i = j;
    }
    // Non-manifold vertices (fans that are not one disk) are locked too.
    for (std::size_t v = 0; v < pos_.size(); ++v)
      if (alive_[v] && !lock_[v] && !is_disk(static_cast<Index>(v))) lock_[v] = true;
  }

  bool wants_boundary_plane(Index a, Index b) const {
    if (params_.locked && a < params_.locked->size() && b < params_.locked->size() && (*params_.locked)[a] &&
        (*params_.locked)[b])
      return false;
    if (params_.quadrics)
      return params_.seam && a < params_.seam->size() && b < params_.seam->size() && (*params_.seam)[a] &&
             (*params_.seam)[b];
    return true;
  }

  static Quadric from_array(const std::array<double, 11>& q) {
    return {q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], q[8], q[9], q[10]};
  }
  static std::array<double, 11> to_array(const Quadric& q) {
    return {q.a2, q.ab, q.ac, q.ad, q.b2, q.bc, q.bd, q.c2, q.cd, q.d2, q.weight};
  }

  // A plane through the boundary edge, perpendicular to its triangle, heavily weighted.
  void add_boundary_plane(Index a, Index b) {
    for (Index t : vt_[a]) {
      const auto& tri = tris_[t];
      if (tri[0] != b && tri[1] != b && tri[2] != b) continue;
      Vec n = cross(sub(pos_[tri[1]], pos_[tri[0]]), sub(pos_[tri[2]], pos_[tri[0]]));
      Vec e = sub(pos_[b], pos_[a]);
      Vec p = cross(e, n);
      double len = std::sqrt(dot(p, p));
      if (len == 0) return;
      Vec u{p[0] / len, p[1] / len, p[2] / len};
      Quadric q;
      q.add_plane(u, -dot(u, pos_[a]), kBoundaryWeight * dot(e, e));
      quadric_[a] += q;
      quadric_[b] += q;
      return;
    }
  }

  // The triangles around v form one fan (a disk or a half-disk).
  bool is_disk(Index v) const {
    const auto& ts = vt_[v];
    if (ts.size() < 1) return true;
    // Count, for each neighbour, how many of v's triangles use the edge (v, neighbour); the fan
    // is one piece iff the number of neighbours is #triangles (closed) or #triangles+1 (open)
    // with every edge used once or twice and exactly two used once when open.
    std::vector<std::pair<Index, int>> count;
    for (Index t : ts)
      for (Index w : tris_[t]) {
        if (w == v) continue;
        auto it = std::find_if(count.begin(), count.end(), [&](auto& p) { return p.first == w; });
        if (it == count.end()) count.emplace_back(w, 1);
        else it->second++;
      }
    int ones = 0;
    for (auto& [w, c] : count) {
      if (c > 2) return false;
      ones += c == 1;
    }
    if (ones == 0) return count.size() == ts.size();
    return ones == 2 && count.size() == ts.size() + 1;
  }

  void neighbours(Index v, std::vector<Index>& out) const {
    out.clear();
    for (Index t : vt_[v])
      for (Index w : tris_[t])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  void push_edges_of(Index v) {
    neighbours(v, scratch_);
    std::vector<Index> around = scratch_;
    for (Index w : around) push_candidate(v, w);
  }

  bool is_boundary_edge(Index a, Index b) const {
    int n = 0;
    for (Index t : vt_[a]) {
      const auto& tri = tris_[t];
      n += tri[0] == b || tri[1] == b || tri[2] == b;
    }
    return n == 1;
  }

  void push_candidate(Index a, Index b) {
    if (lock_[a] || lock_[b]) return;
    if (a > b) std::swap(a, b);
    Quadric q = quadric_[a];
    q += quadric_[b];
    Vec best;
    bool ba = boundary_[a], bb = boundary_[b];
    std::vector<Vec> options;
    Index keep = a, drop = b;
    if (ba != bb) {
      // An interior vertex goes to the boundary one: the boundary stays where it is.
      options.push_back(ba ? pos_[a] : pos_[b]);
      if (bb) keep = b, drop = a;
    } else if (ba && bb && !is_boundary_edge(a, b)) {
      return;  // two boundary vertices joined through the interior: would pinch
    } else {
      Vec opt;
      if (q.optimum(opt)) options.push_back(opt);
      options.push_back(pos_[a]);
      options.push_back(pos_[b]);
      options.push_back({(pos_[a][0] + pos_[b][0]) / 2, (pos_[a][1] + pos_[b][1]) / 2, (pos_[a][2] + pos_[b][2]) / 2});
    }
    double best_cost = INFINITY;
    for (const Vec& x : options) {
      double cost = q.eval(x);
      if (cost < best_cost) best_cost = cost, best = x;
    }
    // The planes' own weight (without the boundary constraints' extra) normalises the error.
    double rms = q.weight > 0 ? std::sqrt(best_cost / q.weight) : 0;
    double rank = params_.max_error > 0 ? rms : best_cost;
    heap_.push({rank, rms, keep, drop, stamp_[keep], stamp_[drop], best});
  }

  bool collapse(const Candidate& c) {
    Index keep = c.keep, drop = c.drop;
    // Triangles on the edge, and the link condition.
    std::vector<Index> shared;
    for (Index t : vt_[keep]) {
      const auto& tri = tris_[t];
      if (tri[0] == drop || tri[1] == drop || tri[2] == drop) shared.push_back(t);
    }
    if (shared.empty() || shared.size() > 2) return false;
    std::vector<Index> nk, nd, common;
    neighbours(keep, nk);
    neighbours(drop, nd);
    std::set_intersection(nk.begin(), nk.end(), nd.begin(), nd.end(), std::back_inserter(common));
    if (common.size() != shared.size()) return false;
    // Keep closed pieces from collapsing below a tetrahedron.
    if (shared.size() == 2 && nk.size() <= 3 && nd.size() <= 3) return false;
    // A boundary loop of three edges would close.
    if (shared.size() == 1 && boundary_[keep] && boundary_[drop]) {
      Index third = common[0];
      if (boundary_[third] && is_boundary_edge(keep, third) && is_boundary_edge(drop, third)) return false;
    }
    // No flipped or degenerate triangle around the new vertex.
    for (Index v : {keep, drop})
      for (Index t : vt_[v]) {
        if (std::find(shared.begin(), shared.end(), t) != shared.end()) continue;
        const auto& tri = tris_[t];
        Vec p[3], q[3];
        for (int k = 0; k < 3; ++k) {
          p[k] = pos_[tri[k]];
          q[k] = (tri[k] == keep || tri[k] == drop) ? c.position : pos_[tri[k]];
        }
        Vec before = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        Vec after = cross(sub(q[1], q[0]), sub(q[2], q[0]));
        double lb = dot(before, before), la = dot(after, after);
        if (la <= 1e-12 * lb || la == 0) return false;
        if (dot(before, after) <= 0.2 * std::sqrt(lb * la)) return false;  // > ~78 degrees turn
      }
    // Apply.
    for (Index t : shared) {
      tri_alive_[t] = false;
      for (Index v : tris_[t]) {
        auto& list = vt_[v];
        list.erase(std::remove(list.begin(), list.end(), t), list.end());
      }
    }
    for (Index t : vt_[drop]) {
      for (Index& v : tris_[t])
        if (v == drop) v = keep;
      vt_[keep].push_back(t);
    }
    vt_[drop].clear();
    alive_[drop] = false;
    live_vertices_--;
    pos_[keep] = c.position;
    quadric_[keep] += quadric_[drop];
    boundary_[keep] = boundary_[keep] || boundary_[drop];
    // Only the edges at `keep` changed cost; others are re-checked when they surface.
    stamp_[keep]++;
    stamp_[drop]++;
    push_edges_of(keep);
    return true;
  }

  mesh::Mesh output(SimplifyResult& result) const {
    mesh::Mesh out;
    std::vector<Index> renumber(pos_.size(), 0);
    std::vector<bool> used(pos_.size(), false);
    for (std::size_t t = 0; t < tris_.size(); ++t)
      if (tri_alive_[t])
        for (Index v : tris_[t]) used[v] = true;
    for (std::size_t v = 0; v < pos_.size(); ++v) {
      if (!used[v]) continue;
      renumber[v] = static_cast<Index>(out.positions.size());
      result.source_ids.push_back(static_cast<Index>(v));
      if (params_.export_quadrics) result.quadrics.push_back(to_array(quadric_[v]));
      out.positions.push_back({static_cast<float>(pos_[v][0]), static_cast<float>(pos_[v][1]), static_cast<float>(pos_[v][2])});
    }
    for (std::size_t t = 0; t < tris_.size(); ++t)
      if (tri_alive_[t]) out.triangles.push_back({renumber[tris_[t][0]], renumber[tris_[t][1]], renumber[tris_[t][2]]});
    return out;
  }

  const SimplifyParams& params_;
  std::vector<Vec> pos_;
  std::vector<mesh::Triangle> tris_;
  std::vector<bool> tri_alive_, alive_, boundary_, lock_;
  std::vector<Index> locked_;
  std::vector<std::vector<Index>> vt_;
  std::vector<Quadric> quadric_;
  std::vector<std::uint32_t> stamp_;
  std::priority_queue<Candidate> heap_;
  std::vector<Index> scratch_;
  std::size_t live_vertices_ = 0;
};

}  // namespace

SimplifyResult simplify(const mesh::Mesh& input, const SimplifyParams& params) {
  if (params.max_error <= 0 && params.target_vertices == 0)
    throw InvalidInput("Simplify needs maxError > 0 or targetVertices > 0");
  Simplifier simplifier(input, params);
  return simplifier.run();
}

}  // namespace meshflow::services
