#include "services/repair.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <map>

#include "mesh/errors.h"
#include "services/cgal_bridge.h"

namespace meshflow::services {
namespace {

using mesh::Index;
using mesh::Point;
using protocol::EditMesh;

// How many rings of triangles around the boundary FillHoles hands to CGAL: the rim's own
// triangles (the refinement's edge lengths) and two more (fairing's cotangent weights and
// Voronoi areas at the rim).
constexpr std::uint8_t kFillRings = 3;

std::uint64_t edge_key(Index a, Index b) { return static_cast<std::uint64_t>(std::min(a, b)) << 32 | std::max(a, b); }

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
      keys.push_back(edge_key(a, b));
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

// Duplicates: triangles with the same vertex set. Each group keeps its first triangle, unless
// keeping none opens fewer boundary edges than keeping one: a triangle doubled back on itself
// (a, b, c) + (a, c, b) hanging from one edge, or copies stacked with nothing else around,
// enclose nothing, and one copy alone would show open edges that the stack hid.
bool remove_duplicate_triangles(EditMesh& m) {
  std::vector<std::pair<std::array<Index, 3>, Index>> sorted;  // (vertex set, triangle id)
  for (auto& [id, t] : live_triangles(m)) {
    std::array<Index, 3> key = t;
    std::sort(key.begin(), key.end());
    sorted.emplace_back(key, id);
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::pair<std::array<Index, 3>, std::vector<Index>>> groups;  // duplicated sets only
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i;
    while (j < sorted.size() && sorted[j].first == sorted[i].first) ++j;
    if (j - i > 1) {
      groups.emplace_back(sorted[i].first, std::vector<Index>{});
      for (std::size_t k = i; k < j; ++k) groups.back().second.push_back(sorted[k].second);
    }
    i = j;
  }
  if (groups.empty()) return false;
  std::map<std::uint64_t, std::uint32_t> uses;  // of the edges of duplicated triangles only
  for (auto& [key, ids] : groups)
    for (int k = 0; k < 3; ++k) uses[edge_key(key[k], key[(k + 1) % 3])] = 0;
  for (auto& [id, t] : live_triangles(m))
    for (int k = 0; k < 3; ++k)
      if (auto it = uses.find(edge_key(t[k], t[(k + 1) % 3])); it != uses.end() && t[k] != t[(k + 1) % 3])
        it->second++;
  bool changed = false;
  for (auto& group : groups) {
    const auto& key = group.first;  // named, not bound: lambdas may not capture bindings before C++20 in clang 14
    auto& ids = group.second;
    auto opened = [&](std::uint32_t removed) {
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        if (key[k] == key[(k + 1) % 3]) continue;
        std::uint32_t before = uses[edge_key(key[k], key[(k + 1) % 3])];
        count += before != 1 && before - removed == 1;
      }
      return count;
    };
    auto removed = static_cast<std::uint32_t>(ids.size() - 1);
    if (opened(removed + 1) < opened(removed)) ++removed;
    for (std::uint32_t i = 0; i < removed; ++i) m.remove_triangle(ids[ids.size() - 1 - i]);
    for (int k = 0; k < 3; ++k)
      if (key[k] != key[(k + 1) % 3]) uses[edge_key(key[k], key[(k + 1) % 3])] -= removed;
    changed = true;
  }
  return changed;
}

// Triangles in depth-first order over shared edges: each next triangle is an unvisited
// neighbour of the most recent triangle that still has one (a new component starts at the
// lowest unvisited id).
std::vector<std::size_t> patch_order(const std::vector<mesh::Triangle>& triangles) {
  std::vector<std::pair<std::uint64_t, std::size_t>> by_edge;
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) by_edge.emplace_back(edge_key(triangles[t][k], triangles[t][(k + 1) % 3]), t);
  std::sort(by_edge.begin(), by_edge.end());
  std::vector<std::size_t> order;
  std::vector<bool> visited(triangles.size(), false);
  std::vector<std::size_t> stack;
  for (std::size_t start = 0; start < triangles.size(); ++start) {
    if (visited[start]) continue;
    stack.push_back(start);
    visited[start] = true;
    order.push_back(start);
    while (!stack.empty()) {
      std::size_t t = stack.back();
      std::size_t next = triangles.size();
      for (int k = 0; k < 3 && next == triangles.size(); ++k) {
        auto key = edge_key(triangles[t][k], triangles[t][(k + 1) % 3]);
        auto it = std::lower_bound(by_edge.begin(), by_edge.end(), std::make_pair(key, std::size_t{0}));
        for (; it != by_edge.end() && it->first == key; ++it)
          if (!visited[it->second]) {
            next = it->second;
            break;
          }
      }
      if (next == triangles.size()) {
        stack.pop_back();
        continue;
      }
      visited[next] = true;
      order.push_back(next);
      stack.push_back(next);
    }
  }
  return order;
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
    bool changed = remove_duplicate_triangles(m);
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
  auto edges = edge_uses(m);
  std::vector<std::uint64_t> boundary;  // sorted: edge_uses is
  for (const auto& [key, count] : edges)
    if (count == 1) boundary.push_back(key);
  if (boundary.empty()) return;  // closed: nothing to fill
  std::size_t V = m.vertex_slots();
  std::vector<std::uint8_t> ring(V, 0);  // 1 + rings away from the boundary, 0: farther
  std::vector<Index> parent(V);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](Index x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::size_t loops = 0;
  for (std::uint64_t key : boundary) {
    auto a = static_cast<Index>(key >> 32), b = static_cast<Index>(key & 0xffffffff);
    for (Index v : {a, b})
      if (!ring[v]) ring[v] = 1, ++loops;
    if (find(a) != find(b)) parent[find(a)] = find(b), --loops;
  }
  if (keep_largest_loop && loops <= 1) return;  // the one loop a height field keeps
  // CGAL gets the triangles within kFillRings rings of the boundary (all Liepa's refinement and
  // fairing look at), not the whole mesh: a large mesh with a few holes costs little.
  auto triangles = live_triangles(m);
  for (std::uint8_t r = 1; r <= kFillRings; ++r)
    for (auto& [id, t] : triangles)
      if (ring[t[0]] == r || ring[t[1]] == r || ring[t[2]] == r)
        for (Index v : t)
          if (!ring[v]) ring[v] = static_cast<std::uint8_t>(r + 1);
  mesh::Mesh current;  // the neighbourhood, vertices renumbered in slot order
  std::vector<Index> slot_of, local(V, 0);
  for (std::size_t v = 0; v < V; ++v)
    if (ring[v]) {
      local[v] = static_cast<Index>(slot_of.size());
      slot_of.push_back(static_cast<Index>(v));
      current.positions.push_back(m.position(static_cast<Index>(v)));
    }
  auto near = [&](Index v) { return ring[v] != 0 && ring[v] <= kFillRings; };
  for (auto& [id, t] : triangles)
    if (near(t[0]) || near(t[1]) || near(t[2])) current.triangles.push_back({local[t[0]], local[t[1]], local[t[2]]});
  for (std::uint64_t& key : boundary)
    key = edge_key(local[key >> 32], local[key & 0xffffffff]);
  std::sort(boundary.begin(), boundary.end());
  cgal::HoleFill fill = cgal::fill_holes(current, keep_largest_loop, boundary);
  const auto first_new = static_cast<Index>(current.positions.size());
  // The patches as a correction codes them best (protocol/correction.h): triangles in
  // depth-first order across shared edges, so that each repeats corners of the last few, and
  // new vertices added in the order the triangles first use them.
  std::vector<std::size_t> order = patch_order(fill.triangles);
  std::vector<Index> new_slot(fill.vertices.size(), 0);
  std::vector<bool> added(fill.vertices.size(), false);
  for (std::size_t t : order)
    for (Index v : fill.triangles[t])
      if (v >= first_new && !added[v - first_new]) {
        added[v - first_new] = true;
        new_slot[v - first_new] = m.add_vertex(fill.vertices[v - first_new]);
      }
  for (std::size_t k = 0; k < fill.vertices.size(); ++k)
    if (!added[k]) new_slot[k] = m.add_vertex(fill.vertices[k]);  // none expected: every new vertex is used
  for (std::size_t t : order) {
    mesh::Triangle s;
    for (int k = 0; k < 3; ++k) {
      Index v = fill.triangles[t][k];
      s[k] = v < first_new ? slot_of[v] : new_slot[v - first_new];
    }
    m.add_triangle(s[0], s[1], s[2]);
  }
}

}  // namespace meshflow::services
