#include "services/simplify.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

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
constexpr Index kNoCorner = std::numeric_limits<Index>::max();

// The triangles around each vertex as linked lists through the triangles' corners (corner
// 3t+k is vertex k of triangle t): 4 bytes per corner and per vertex, no allocation per vertex,
// and a collapse hands the dropped vertex's triangles to the kept one by splicing.
class VertexFans {
 public:
  VertexFans(const std::vector<mesh::Triangle>& triangles, std::size_t vertices, const std::vector<bool>& skip)
      : head_(vertices, kNoCorner), next_(3 * triangles.size(), kNoCorner) {
    for (std::size_t t = triangles.size(); t-- > 0;) {
      if (skip[t]) continue;
      for (Index k = 0; k < 3; ++k) {
        Index c = static_cast<Index>(3 * t + k), v = triangles[t][k];
        next_[c] = head_[v];
        head_[v] = c;
      }
    }
  }
  class Iterator {
   public:
    Iterator(const VertexFans* fans, Index corner) : fans_(fans), corner_(corner) {}
    Index operator*() const { return corner_ / 3; }
    Iterator& operator++() {
      corner_ = fans_->next_[corner_];
      return *this;
    }
    bool operator!=(const Iterator& o) const { return corner_ != o.corner_; }

   private:
    const VertexFans* fans_;
    Index corner_;
  };
  struct Range {
    const VertexFans* fans;
    Index first;
    Iterator begin() const { return {fans, first}; }
    Iterator end() const { return {fans, kNoCorner}; }
  };
  Range operator[](Index v) const { return {this, head_[v]}; }
  bool empty(Index v) const { return head_[v] == kNoCorner; }
  std::size_t count(Index v) const {
    std::size_t n = 0;
    for (Index c = head_[v]; c != kNoCorner; c = next_[c]) ++n;
    return n;
  }
  // Unlinks triangle t from v's fan (t must be in it).
  void remove(Index v, Index t) {
    for (Index* link = &head_[v]; *link != kNoCorner; link = &next_[*link])
      if (*link / 3 == t) {
        *link = next_[*link];
        return;
      }
  }
  // Moves every triangle of `from` to `to`, renaming the corner in `triangles`.
  void move_all(Index from, Index to, std::vector<mesh::Triangle>& triangles) {
    Index last = kNoCorner;
    for (Index c = head_[from]; c != kNoCorner; c = next_[c]) {
      triangles[c / 3][c % 3] = to;
      last = c;
    }
    if (last == kNoCorner) return;
    next_[last] = head_[to];
    head_[to] = head_[from];
    head_[from] = kNoCorner;
  }

 private:
  std::vector<Index> head_, next_;
};

// A 4-ary min-heap: half the levels of a binary one, and a node's children share cache lines,
// which matters because the heap's cache misses are most of a simplification's time.
template <typename T, typename Less>
class QuaternaryHeap {
 public:
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  void reserve(std::size_t n) { items_.reserve(n); }
  // Appends without ordering; call heapify() before the next pop.
  void append(const T& item) { items_.push_back(item); }
  void heapify() {
    for (std::size_t i = items_.size() / 4 + 1; i-- > 0;) sift_down(i);
  }
  void push(const T& item) {
    items_.push_back(item);
    std::size_t i = items_.size() - 1;
    while (i > 0) {
      std::size_t parent = (i - 1) / 4;
      if (!less_(items_[i], items_[parent])) break;
      std::swap(items_[i], items_[parent]);
      i = parent;
    }
  }
  T pop() {
    T top = items_.front();
    items_.front() = items_.back();
    items_.pop_back();
    if (!items_.empty()) sift_down(0);
    return top;
  }
  template <typename Pred>
  void remove_if(Pred pred) {
    items_.erase(std::remove_if(items_.begin(), items_.end(), pred), items_.end());
    heapify();
  }

 private:
  void sift_down(std::size_t i) {
    const std::size_t n = items_.size();
    T item = items_[i];
    for (;;) {
      std::size_t first = 4 * i + 1;
      if (first >= n) break;
      std::size_t best = first;
      for (std::size_t c = first + 1; c < std::min(first + 4, n); ++c)
        if (less_(items_[c], items_[best])) best = c;
      if (!less_(items_[best], item)) break;
      items_[i] = items_[best];
      i = best;
    }
    items_[i] = item;
  }
  std::vector<T> items_;
  Less less_;
};

class Simplifier {
 public:
  Simplifier(const mesh::Mesh& input, const SimplifyParams& params) : params_(params) {
    std::size_t V = input.positions.size();
    pos_ = input.positions;
    tris_ = input.triangles;
    tri_alive_.assign(tris_.size(), true);
    quadric_.resize(V);
    if (params_.merged_into) replay_merges(*params_.merged_into);
    std::vector<bool> degenerate(tris_.size(), false);
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& tri = tris_[t];
      if (!tri_alive_[t]) {
        degenerate[t] = true;  // gone with a merge
      } else if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
        // Degenerate by index: kept as is, its vertices locked.
        for (Index v : tri) locked_.push_back(v);
        degenerate[t] = true;
      }
    }
    vt_ = VertexFans(tris_, V, degenerate);
    boundary_.assign(V, false);
    std::vector<bool> lock(V, false);
    for (Index v : locked_) lock[v] = true;
    lock_ = std::move(lock);
    fixed_.assign(V, false);
    if (params_.locked)
      for (std::size_t v = 0; v < V && v < params_.locked->size(); ++v)
        if ((*params_.locked)[v]) fixed_[v] = true;
    if (params_.seam_partner) {
      if (params_.seam_partner->size() != V) throw InvalidInput("Simplify: one seam partner per vertex is needed");
      partner_ = params_.seam_partner->data();
    }
    alive_.assign(V, false);
    for (std::size_t v = 0; v < V; ++v) alive_[v] = !vt_.empty(static_cast<Index>(v));
    version_.assign(V, 0);
    if (params_.quadrics) {
      for (std::size_t v = 0; v < V && v < params_.quadrics->size(); ++v) quadric_[v] = from_array((*params_.quadrics)[v]);
    } else if (!params_.merged_into) {
      add_face_planes();
    }
    classify_edges();
    live_vertices_ = static_cast<std::size_t>(std::count(alive_.begin(), alive_.end(), true));
  }

  // Each live triangle's plane, weighted by its area, to its corners' quadrics.
  void add_face_planes() {
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      const auto& tri = tris_[t];
      if (!tri_alive_[t] || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      Vec n = cross(sub(at(tri[1]), at(tri[0])), sub(at(tri[2]), at(tri[0])));
      double len = std::sqrt(dot(n, n));
      if (len == 0) continue;
      Vec u{n[0] / len, n[1] / len, n[2] / len};
      double area = 0.5 * len;
      Quadric q;
      q.add_plane(u, -dot(u, at(tri[0])), area);
      q.weight = area;
      for (Index v : tri) quadric_[v] += q;
    }
  }

  // Merges made elsewhere before this run (a neighbour part's Rem file): the quadrics come from
  // the triangles as they were, a merged vertex's to the one it joined, so that the error
  // already spent counts; then the triangles are renamed and the degenerate ones dropped.
  void replay_merges(const std::vector<Index>& root) {
    const std::size_t V = pos_.size();
    if (root.size() != V) throw InvalidInput("Simplify: one merge target per vertex is needed");
    for (std::size_t v = 0; v < V; ++v)
      if (root[v] >= V || root[root[v]] != root[v]) throw InvalidInput("Simplify: merge targets must be final");
    add_face_planes();
    for (std::size_t v = 0; v < V; ++v)
      if (root[v] != v) {
        quadric_[root[v]] += quadric_[v];
        quadric_[v] = {};
      }
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      auto& tri = tris_[t];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;  // kept as is, below
      for (Index& v : tri) v = root[v];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) tri_alive_[t] = false;
    }
  }

  SimplifyResult run() {
    // Edges are about 1.5 x triangles; compact() keeps the heap under 1.125 x its live size, so
    // this one allocation holds it to the end.
    heap_.reserve(tris_.size() * 27 / 16 + 1024);
    for (std::size_t v = 0; v < pos_.size(); ++v)
      if (alive_[v]) push_edges_of(static_cast<Index>(v), /*only_greater=*/true);
    heap_.heapify();
    compact_at_ = std::max<std::size_t>(heap_.size() * 9 / 8, 1024);
    max_quadric_ = max_quadric(params_.max_error);
    max_quadric_bits_ = std::bit_cast<std::uint32_t>(static_cast<float>(max_quadric_)) & ~std::uint32_t{0xff};
    SimplifyResult result;
    std::size_t start_vertices = live_vertices_;
    while (!heap_.empty()) {
      if (params_.target_vertices && live_vertices_ <= params_.target_vertices) break;
      Candidate c = heap_.pop();
      if (stale(c)) continue;  // an end changed since, and the edge was pushed again with its new cost
      Placement place;
      if (!evaluate(c.keep, c.drop, place) || place.keep != c.keep || (key_of(place) ^ c.key) > 0xff)
        continue;  // looked current only because the 8-bit versions wrapped
      if (params_.max_error > 0) {
        // Keys keep 15 bits of mantissa: stop once past the quadric bound's key, skip an entry
        // above it that shares its key; skip a collapse beyond the rms bound.
        if (place.cost > max_quadric_) {
          if ((c.key & ~std::uint32_t{0xff}) > max_quadric_bits_) break;
          continue;
        }
        if (place.rms > params_.max_error) continue;
      }
      if (!collapse(c.keep, c.drop, place.position)) continue;
      if (partner_ && partner_[c.drop] != kNoPartner) result.seam_collapses.emplace_back(c.drop, c.keep);
      result.collapses++;
      result.max_rms_error = std::max(result.max_rms_error, place.rms);
      if (heap_.size() > compact_at_) compact();
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
  struct Placement {
    double cost = 0, rms = 0;
    Index keep = 0, drop = 0;
    Vec position{};
  };
  // A collapse in the heap, 12 bytes (the heap's cache misses are most of the time). The key
  // orders the heap: the cost's float in the top 24 bits (non-negative floats order like their
  // bits; 15 bits of mantissa are left), then the sum of the ends' 8-bit versions at push time.
  // Lazy deletion: a collapse changes only the kept vertex (position, quadric, boundary flag),
  // kills the dropped one and pushes the kept vertex's edges again with a new version, so an
  // entry whose version sum no longer matches is stale. The versions wrap; the rare entry that
  // looks current after 256 changes is caught when it surfaces by a fresh evaluation.
  struct Candidate {
    std::uint32_t key;
    Index keep, drop;
  };
  struct Cheaper {
    bool operator()(const Candidate& a, const Candidate& b) const { return a.key < b.key; }
  };
  std::uint32_t key_of(const Placement& p) const {
    return (std::bit_cast<std::uint32_t>(static_cast<float>(p.cost)) & ~std::uint32_t{0xff}) | version_sum(p.keep, p.drop);
  }
  std::uint8_t version_sum(Index a, Index b) const { return static_cast<std::uint8_t>(version_[a] + version_[b]); }

  bool stale(const Candidate& c) const {
    return !alive_[c.keep] || !alive_[c.drop] || (c.key & 0xff) != version_sum(c.keep, c.drop);
  }
  // Drops the stale candidates so that the heap stays proportional to the live edges.
  void compact() {
    heap_.remove_if([&](const Candidate& c) { return stale(c); });
    compact_at_ = std::max<std::size_t>(heap_.size() * 9 / 8, 1024);
  }

  // Boundary edges (one triangle) get a constraint plane; vertices on non-manifold edges (3+
  // triangles) or whose triangles are not one fan are locked. Found from each vertex's
  // triangles, without an edge table.
  void classify_edges() {
    std::vector<std::pair<Index, int>>& count = edge_count_;
    for (std::size_t vi = 0; vi < pos_.size(); ++vi) {
      const Index v = static_cast<Index>(vi);
      if (!alive_[v]) continue;
      count_edges(v, count);
      for (auto [w, c] : count) {
        if (c == 1) {
          boundary_[v] = boundary_[w] = true;
          if (v < w && wants_boundary_plane(v, w)) add_boundary_plane(v, w);
        } else if (c > 2) {
          lock_[v] = lock_[w] = true;  // non-manifold edge
        }
      }
      if (!lock_[v] && !is_disk(v, count)) lock_[v] = true;  // not one fan
    }
  }

  // For each neighbour w of v, the number of v's triangles on the edge (v, w).
  void count_edges(Index v, std::vector<std::pair<Index, int>>& count) const {
    count.clear();
    for (Index t : vt_[v])
      for (Index w : tris_[t]) {
        if (w == v) continue;
        auto it = std::find_if(count.begin(), count.end(), [&](auto& p) { return p.first == w; });
        if (it == count.end()) count.emplace_back(w, 1);
        else it->second++;
      }
  }

  // Whether v is on a seam between parts: locked by the caller, or free to go to a partner.
  bool on_seam(Index v) const {
    return (params_.locked && v < params_.locked->size() && (*params_.locked)[v]) || (partner_ && partner_[v] != kNoPartner);
  }

  bool wants_boundary_plane(Index a, Index b) const {
    if (on_seam(a) && on_seam(b)) return false;  // a seam, not a border of the surface
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
      Vec n = cross(sub(at(tri[1]), at(tri[0])), sub(at(tri[2]), at(tri[0])));
      Vec e = sub(at(b), at(a));
      Vec p = cross(e, n);
      double len = std::sqrt(dot(p, p));
      if (len == 0) return;
      Vec u{p[0] / len, p[1] / len, p[2] / len};
      Quadric q;
      q.add_plane(u, -dot(u, at(a)), kBoundaryWeight * dot(e, e));
      quadric_[a] += q;
      quadric_[b] += q;
      return;
    }
  }

  // The triangles around v form one fan (a disk or a half-disk): the number of neighbours is
  // #triangles (closed) or #triangles+1 (open), every edge used once or twice, and exactly two
  // used once when open. `count` is count_edges(v).
  bool is_disk(Index v, const std::vector<std::pair<Index, int>>& count) const {
    if (vt_.empty(v)) return true;
    const std::size_t triangles = vt_.count(v);
    int ones = 0;
    for (auto& [w, c] : count) {
      if (c > 2) return false;
      ones += c == 1;
    }
    if (ones == 0) return count.size() == triangles;
    return ones == 2 && count.size() == triangles + 1;
  }

  void neighbours(Index v, std::vector<Index>& out) const {
    out.clear();
    for (Index t : vt_[v])
      for (Index w : tris_[t])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  // Pushes the collapses of v's edges (with only_greater, those to higher ids: each edge once
  // when called for every vertex, and without keeping the heap ordered: run() heapifies).
  void push_edges_of(Index v, bool only_greater = false) {
    neighbours(v, around_);
    for (Index w : around_)
      if (!only_greater || w > v) push_candidate(v, w, !only_greater);
  }

  bool is_boundary_edge(Index a, Index b) const {
    int n = 0;
    for (Index t : vt_[a]) {
      const auto& tri = tris_[t];
      n += tri[0] == b || tri[1] == b || tri[2] == b;
    }
    return n == 1;
  }

  // The collapse of edge (a, b): which end stays, where it goes, at what cost. False when the
  // edge may not collapse at all.
  bool evaluate(Index a, Index b, Placement& out) const {
    if (lock_[a] || lock_[b] || (fixed_[a] && fixed_[b])) return false;
    if (a > b) std::swap(a, b);
    if (partner_ && (partner_[a] != kNoPartner || partner_[b] != kNoPartner)) return evaluate_seam(a, b, out);
    Quadric q = quadric_[a];
    q += quadric_[b];
    bool ba = boundary_[a], bb = boundary_[b];
    Vec options[4];
    int n = 0;
    out.keep = a, out.drop = b;
    if (fixed_[a] || fixed_[b]) {
      // Into the fixed end, which stays where it is (a seam vertex of a part absorbs its
      // neighbours); a boundary vertex goes only along its boundary.
      const Index keep = fixed_[a] ? a : b, drop = fixed_[a] ? b : a;
      if (boundary_[drop] && (!boundary_[keep] || !is_boundary_edge(a, b))) return false;
      out.keep = keep, out.drop = drop;
      options[n++] = at(keep);
    } else if (ba != bb) {
      // An interior vertex goes to the boundary one: the boundary stays where it is.
      options[n++] = ba ? at(a) : at(b);
      if (bb) out.keep = b, out.drop = a;
    } else if (ba && bb && !is_boundary_edge(a, b)) {
      return false;  // two boundary vertices joined through the interior: would pinch
    } else {
      if (q.optimum(options[n])) ++n;
      options[n++] = at(a);
      options[n++] = at(b);
      {
        Vec pa = at(a), pb = at(b);
        options[n++] = {(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2};
      }
    }
    out.cost = INFINITY;
    for (int i = 0; i < n; ++i) {
      mesh::Point stored = to_float(options[i]);
      options[i] = {stored[0], stored[1], stored[2]};
      double cost = q.eval(options[i]);
      if (cost < out.cost) out.cost = cost, out.position = options[i];
    }
    // The planes' own weight (without the boundary constraints' extra) normalises the error.
    out.rms = q.weight > 0 ? std::sqrt(out.cost / q.weight) : 0;
    return true;
  }

  // An edge with a seam end (a < b): a half-edge collapse that leaves the seam end in place; two
  // seam ends only along the part's border and with the same partner, which will replay it.
  // Allocates nothing; only called when seam partners are given.
  bool evaluate_seam(Index a, Index b, Placement& out) const {
    // A fixed vertex (params.locked) is never removed, and a seam vertex goes only onto another
    // of the same seam, which the partner holds too.
    if (fixed_[a] || fixed_[b]) return false;
    const std::uint32_t pa = partner_[a], pb = partner_[b];
    Quadric q = quadric_[a];
    q += quadric_[b];
    if (pa != kNoPartner && pb != kNoPartner) {
      if (pa != pb || !is_boundary_edge(a, b)) return false;
      // The partner's side of the collapse is unseen here (where this part's side may cost
      // nothing at all, at a vertex with one triangle in the part): it is estimated by the
      // reverse move's cost, the kept vertex's planes at the removed one.
      const double ca = q.eval(at(a)) + quadric_[a].eval(at(b)), cb = q.eval(at(b)) + quadric_[b].eval(at(a));
      if (ca <= cb) out.keep = a, out.drop = b, out.cost = ca;
      else out.keep = b, out.drop = a, out.cost = cb;
    } else {
      out.keep = pa != kNoPartner ? a : b;
      out.drop = pa != kNoPartner ? b : a;
      // Both on the border (the seam vertex always is) through the interior: would pinch.
      if (boundary_[out.drop] && !is_boundary_edge(a, b)) return false;
      out.cost = q.eval(at(out.keep));
    }
    out.position = at(out.keep);
    out.rms = q.weight > 0 ? std::sqrt(out.cost / q.weight) : 0;
    return true;
  }

  void push_candidate(Index a, Index b, bool keep_heap_order) {
    Placement p;
    if (!evaluate(a, b, p)) return;
    const Candidate c{key_of(p), p.keep, p.drop};
    if (keep_heap_order) heap_.push(c);
    else heap_.append(c);
  }

  bool collapse(Index keep, Index drop, const Vec& position) {
    // Triangles on the edge, and the link condition.
    std::vector<Index>& shared = shared_;
    shared.clear();
    for (Index t : vt_[keep]) {
      const auto& tri = tris_[t];
      if (tri[0] == drop || tri[1] == drop || tri[2] == drop) shared.push_back(t);
    }
    if (shared.empty() || shared.size() > 2) return false;
    std::vector<Index>&nk = nk_, &nd = nd_, &common = common_;
    common.clear();
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
          p[k] = at(tri[k]);
          q[k] = (tri[k] == keep || tri[k] == drop) ? position : at(tri[k]);
        }
        Vec before = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        Vec after = cross(sub(q[1], q[0]), sub(q[2], q[0]));
        double lb = dot(before, before), la = dot(after, after);
        if (la <= 1e-12 * lb || la == 0) return false;
        if (dot(before, after) <= 0.2 * std::sqrt(lb * la)) return false;  // > ~78 degrees turn
      }
    const bool seam = partner_ && partner_[drop] != kNoPartner;
    if (seam && params_.seam_side && !params_.seam_side->allows(drop, keep, common[0], nk, nd)) return false;
    // Apply.
    for (Index t : shared) {
      tri_alive_[t] = false;
      for (Index v : tris_[t]) vt_.remove(v, t);
    }
    vt_.move_all(drop, keep, tris_);
    alive_[drop] = false;
    live_vertices_--;
    version_[keep]++;
    pos_[keep] = to_float(position);
    quadric_[keep] += quadric_[drop];
    boundary_[keep] = boundary_[keep] || boundary_[drop];
    if (seam && params_.seam_side) params_.seam_side->collapsed(drop, keep);
    // Only the edges at `keep` changed cost; the old entries are dropped when they surface.
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
      out.positions.push_back(pos_[v]);
    }
    for (std::size_t t = 0; t < tris_.size(); ++t)
      if (tri_alive_[t]) out.triangles.push_back({renumber[tris_[t][0]], renumber[tris_[t][1]], renumber[tris_[t][2]]});
    return out;
  }

  Vec at(Index v) const { return {pos_[v][0], pos_[v][1], pos_[v][2]}; }
  static mesh::Point to_float(const Vec& v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
  }

  const SimplifyParams& params_;
  const std::uint32_t* partner_ = nullptr;  // params_.seam_partner's, or null
  std::vector<mesh::Point> pos_;  // float32 like the output: a placement is rounded before it is costed
  std::vector<mesh::Triangle> tris_;
  std::vector<bool> tri_alive_, alive_, boundary_;
  std::vector<bool> lock_;   // never touched: degenerate triangles' and non-manifold vertices
  std::vector<bool> fixed_;  // params.locked: never moved nor removed, but may absorb a neighbour
  std::vector<Index> locked_;
  VertexFans vt_{{}, 0, {}};
  std::vector<Quadric> quadric_;
  QuaternaryHeap<Candidate, Cheaper> heap_;
  std::size_t compact_at_ = 0;
  std::vector<std::uint8_t> version_;  // per vertex, wrapping: bumped when a collapse changes it
  double max_quadric_ = 0;              // max_quadric(params.max_error)
  std::uint32_t max_quadric_bits_ = 0;  // max_quadric_ in the keys' cost bits
  std::vector<Index> around_, shared_, nk_, nd_, common_;
  std::vector<std::pair<Index, int>> edge_count_;  // scratch, kept to avoid allocations
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
