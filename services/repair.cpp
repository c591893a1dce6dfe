#include "services/repair.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include "mesh/errors.h"
#include "services/cgal_bridge.h"

namespace meshflow::services {
namespace {

using mesh::Index;
using mesh::Point;
using protocol::EditMesh;

// Live triangles of the mesh as (id, triangle) pairs.
std::vector<std::pair<Index, mesh::Triangle>> live_triangles(const EditMesh& m) {
  std::vector<std::pair<Index, mesh::Triangle>> out;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    if (m.triangle_alive(static_cast<Index>(t))) out.emplace_back(static_cast<Index>(t), m.triangle(static_cast<Index>(t)));
  return out;
}

// Undirected edges (u < v) with how many triangles use each.
std::vector<std::pair<std::uint64_t, std::uint32_t>> edge_uses(const EditMesh& m) {
  std::vector<std::uint64_t> keys;
  for (auto& [id, t] : live_triangles(m))
    for (int k = 0; k < 3; ++k) {
      Index a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      keys.push_back(static_cast<std::uint64_t>(std::min(a, b)) << 32 | std::max(a, b));
    }
  std::sort(keys.begin(), keys.end());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> out;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    out.emplace_back(keys[i], static_cast<std::uint32_t>(j - i));
    i = j;
  }
  return out;
}

double length2(const Point& a, const Point& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s += (double(a[k]) - b[k]) * (double(a[k]) - b[k]);
  return s;
}

}  // namespace

void remove_smallest_components(EditMesh& m) {
  std::size_t V = m.vertex_slots();
  std::vector<Index> parent(V);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](Index x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto triangles = live_triangles(m);
  for (auto& [id, t] : triangles)
    for (int k = 1; k < 3; ++k) {
      Index a = find(t[0]), b = find(t[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<std::uint64_t> size(V, 0);
  for (auto& [id, t] : triangles) size[find(t[0])]++;
  Index keep = 0;
  for (std::size_t v = 0; v < V; ++v)
    if (size[v] > size[keep]) keep = static_cast<Index>(v);
  if (triangles.empty()) return;
  std::vector<bool> used(V, false);
  for (auto& [id, t] : triangles) {
    if (find(t[0]) != keep) m.remove_triangle(id);
    else for (Index v : t) used[v] = true;
  }
  for (std::size_t v = 0; v < V; ++v)
    if (m.vertex_alive(static_cast<Index>(v)) && !used[v]) m.remove_vertex(static_cast<Index>(v));
}

void laplacian_smoothing(EditMesh& m, int iterations, const std::atomic<bool>* cancel) {
  if (iterations < 1) throw InvalidInput("iterations must be at least 1, got " + std::to_string(iterations));
  std::size_t V = m.vertex_slots();
  auto edges = edge_uses(m);
  std::vector<bool> fixed(V, true);  // unreferenced vertices stay put
  std::vector<std::uint32_t> degree(V, 0);
  for (auto& [key, uses] : edges) {
    Index a = static_cast<Index>(key >> 32), b = static_cast<Index>(key & 0xffffffff);
    degree[a]++, degree[b]++;
  }
  for (std::size_t v = 0; v < V; ++v) fixed[v] = degree[v] == 0;
  for (auto& [key, uses] : edges)
    if (uses == 1) fixed[key >> 32] = fixed[key & 0xffffffff] = true;  // boundary vertices
  // Neighbour lists (CSR).
  std::vector<std::uint64_t> offsets(V + 1, 0);
  for (std::size_t v = 0; v < V; ++v) offsets[v + 1] = offsets[v] + degree[v];
  std::vector<Index> neighbours(offsets[V]);
  std::vector<std::uint64_t> fill(offsets.begin(), offsets.end() - 1);
  for (auto& [key, uses] : edges) {
    Index a = static_cast<Index>(key >> 32), b = static_cast<Index>(key & 0xffffffff);
    neighbours[fill[a]++] = b;
    neighbours[fill[b]++] = a;
  }
  std::vector<Point> current(V), next(V);
  for (std::size_t v = 0; v < V; ++v) current[v] = m.position(static_cast<Index>(v));
  for (int it = 0; it < iterations; ++it) {
    if (cancel && cancel->load()) throw std::runtime_error("cancelled");
    for (std::size_t v = 0; v < V; ++v) {
      if (fixed[v]) {
        next[v] = current[v];
        continue;
      }
      double sum[3] = {0, 0, 0};
      for (std::uint64_t k = offsets[v]; k < offsets[v + 1]; ++k)
        for (int c = 0; c < 3; ++c) sum[c] += current[neighbours[k]][c];
      double n = static_cast<double>(degree[v]);
      next[v] = {static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n), static_cast<float>(sum[2] / n)};
    }
    std::swap(current, next);
  }
  std::vector<Point> live;
  live.reserve(V);
  for (std::size_t v = 0; v < V; ++v)
    if (m.vertex_alive(static_cast<Index>(v))) live.push_back(current[v]);
  m.move_all_vertices(std::move(live));
}

void add_noise(EditMesh& m, double max_distance, std::uint64_t seed) {
  std::size_t V = m.vertex_slots();
  std::vector<std::array<double, 3>> normal(V, {0, 0, 0});
  for (auto& [id, t] : live_triangles(m)) {
    const Point &a = m.position(t[0]), &b = m.position(t[1]), &c = m.position(t[2]);
    double u[3], w[3];
    for (int k = 0; k < 3; ++k) u[k] = double(b[k]) - a[k], w[k] = double(c[k]) - a[k];
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    for (Index v : t)
      for (int k = 0; k < 3; ++k) normal[v][k] += n[k];  // area-weighted (|n| = 2 area)
  }
  std::mt19937_64 rng(seed);
  std::vector<Point> live;
  for (std::size_t v = 0; v < V; ++v) {
    double r = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0,1)
    if (!m.vertex_alive(static_cast<Index>(v))) continue;
    Point p = m.position(static_cast<Index>(v));
    double len = std::sqrt(normal[v][0] * normal[v][0] + normal[v][1] * normal[v][1] + normal[v][2] * normal[v][2]);
    if (len > 0) {
      double d = (2 * r - 1) * max_distance / len;
      for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(p[k] + d * normal[v][k]);
    }
    live.push_back(p);
  }
  m.move_all_vertices(std::move(live));
}

void remove_degenerate_triangles(EditMesh& m) {
  constexpr int kMaxPasses = 20;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    bool changed = false;
    // Duplicates: the same vertex set; keep the first.
    std::set<std::array<Index, 3>> seen;
    for (auto& [id, t] : live_triangles(m)) {
      std::array<Index, 3> key = t;
      std::sort(key.begin(), key.end());
      if (!seen.insert(key).second) {
        m.remove_triangle(id);
        changed = true;
      }
    }
    for (auto& [id, t0] : live_triangles(m)) {
      if (!m.triangle_alive(id)) continue;
      mesh::Triangle t = m.triangle(id);
      const Point &a = m.position(t[0]), &b = m.position(t[1]), &c = m.position(t[2]);
      // A zero-length edge: a repeated vertex, or two corners at the same point.
      int short_edge = -1;
      for (int k = 0; k < 3; ++k)
        if (t[k] == t[(k + 1) % 3] || m.position(t[k]) == m.position(t[(k + 1) % 3])) short_edge = k;
      if (short_edge >= 0) {
        Index x = t[short_edge], y = t[(short_edge + 1) % 3];
        if (x == y) {
          m.remove_triangle(id);  // a repeated index: its other edges are a doubled segment
        } else {
          m.collapse_edge(std::min(x, y), std::max(x, y));
        }
        changed = true;
        continue;
      }
      if (!cgal::collinear(a, b, c)) continue;
      // Collinear: flip the longest edge (the one the third corner lies on).
      int longest = 0;
      double best = -1;
      for (int k = 0; k < 3; ++k) {
        double l = length2(m.position(t[k]), m.position(t[(k + 1) % 3]));
        if (l > best) best = l, longest = k;
      }
      Index x = t[longest], y = t[(longest + 1) % 3];
      Index corner = t[(longest + 2) % 3];
      auto across = m.triangles_of_edge(x, y);
      auto collapse_corner = [&] {
        // The corner lying on the long edge goes to the nearer end of it.
        Index near = length2(m.position(corner), m.position(x)) <= length2(m.position(corner), m.position(y)) ? x : y;
        m.collapse_edge(std::min(near, corner), std::max(near, corner),
                        near < corner ? std::nullopt : std::optional<Point>(m.position(near)));
      };
      bool fin = m.triangles_of_edge(x, corner).size() == 1 && m.triangles_of_edge(y, corner).size() == 1;
      if (across.size() == 1 || fin) {
        // On the boundary, or a fin whose short edges nothing else uses: its two short edges
        // span the same segment as its long one, so removing it opens no hole.
        m.remove_triangle(id);
        changed = true;
      } else if (across.size() > 2) {
        collapse_corner();
        changed = true;
      } else {
        Index other = across[0] == id ? across[1] : across[0];
        const auto& o = m.triangle(other);
        Index d = o[0] + o[1] + o[2] - x - y;
        Index opposite = t[(longest + 2) % 3];
        // Flipping makes (x, d, c) and (d, y, c): only when that does not create a collinear
        // triangle or an existing edge.
        if (d != opposite && m.triangles_of_edge(d, opposite).empty() &&
            !cgal::collinear(m.position(x), m.position(d), m.position(opposite)) &&
            !cgal::collinear(m.position(d), m.position(y), m.position(opposite))) {
          try {
            m.swap_edge(x, y);
            changed = true;
          } catch (const InvalidInput&) {
            // Inconsistently oriented neighbours: leave it for the next rule.
          }
        } else {
          collapse_corner();
          changed = true;
        }
      }
    }
    if (!changed) break;
  }
}

void fill_holes(EditMesh& m, bool keep_largest_loop) {
  mesh::Mesh current = m.compact();
  // compact() renumbers; map its ids back to the slots of the mesh under edit.
  std::vector<Index> slot_of;
  for (std::size_t v = 0; v < m.vertex_slots(); ++v)
    if (m.vertex_alive(static_cast<Index>(v))) slot_of.push_back(static_cast<Index>(v));
  cgal::HoleFill fill = cgal::fill_holes(current, keep_largest_loop);
  std::vector<Index> new_slot;
  for (const Point& p : fill.vertices) new_slot.push_back(m.add_vertex(p));
  for (const auto& t : fill.triangles) {
    mesh::Triangle s;
    for (int k = 0; k < 3; ++k)
      s[k] = t[k] < current.positions.size() ? slot_of[t[k]] : new_slot[t[k] - current.positions.size()];
    m.add_triangle(s[0], s[1], s[2]);
  }
}

}  // namespace meshflow::services
