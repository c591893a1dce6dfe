#include "mesh/measures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "mesh/errors.h"

namespace meshflow::mesh {
namespace {

using Vec = std::array<double, 3>;

Vec sub(const Point& a, const Point& b) {
  return {double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]};
}
Vec cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

// Union-find over 32-bit ids with path halving; `parity` variant tracks the relative flip
// of each element to its root (orientability).
class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) {
    for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<Index>(i);
  }
  Index find(Index x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(Index a, Index b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<Index> parent_;
};

class ParityUnionFind {
 public:
  explicit ParityUnionFind(std::size_t n) : parent_(n), parity_(n, 0), rank_(n, 0) {
    for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<Index>(i);
  }
  // Root of x and the parity of x relative to it (union by rank keeps paths short).
  std::pair<Index, std::uint8_t> find(Index x) const {
    std::uint8_t p = 0;
    while (parent_[x] != x) {
      p ^= parity_[x];
      x = parent_[x];
    }
    return {x, p};
  }
  // Requires parity(a) ^ parity(b) == relation; false on a contradiction.
  bool relate(Index a, Index b, std::uint8_t relation) {
    auto [ra, pa] = find(a);
    auto [rb, pb] = find(b);
    if (ra == rb) return (pa ^ pb) == relation;
    if (rank_[ra] < rank_[rb]) std::swap(ra, rb);
    parent_[rb] = ra;
    parity_[rb] = pa ^ pb ^ relation;
    if (rank_[ra] == rank_[rb]) rank_[ra]++;
    return true;
  }

 private:
  std::vector<Index> parent_;
  std::vector<std::uint8_t> parity_;
  std::vector<std::uint8_t> rank_;
};

double angle_deg(const Vec& u, const Vec& v) {
  return std::atan2(norm(cross(u, v)), dot(u, v)) * 180.0 / std::numbers::pi;
}

std::string json_number(double value) {
  if (!std::isfinite(value)) value = 0;
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

}  // namespace

Measures compute_measures(const Mesh& mesh) {
  Measures m;
  const std::size_t V = mesh.positions.size();
  const std::size_t T = mesh.triangles.size();
  m.vertices = V;
  m.triangles = T;
  for (const Triangle& t : mesh.triangles)
    for (Index v : t) MESHFLOW_ASSERT(v < V, "triangle index out of range");

  // Vertex -> triangle incidence (CSR), one entry per distinct vertex of a triangle.
  std::vector<std::uint64_t> offsets(V + 1, 0);
  for (const Triangle& t : mesh.triangles) {
    offsets[t[0] + 1]++;
    if (t[1] != t[0]) offsets[t[1] + 1]++;
    if (t[2] != t[0] && t[2] != t[1]) offsets[t[2] + 1]++;
  }
  for (std::size_t v = 0; v < V; ++v) offsets[v + 1] += offsets[v];
  std::vector<Index> incident(offsets[V]);
  {
    std::vector<std::uint64_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < T; ++i) {
      const Triangle& t = mesh.triangles[i];
      incident[fill[t[0]]++] = static_cast<Index>(i);
      if (t[1] != t[0]) incident[fill[t[1]]++] = static_cast<Index>(i);
      if (t[2] != t[0] && t[2] != t[1]) incident[fill[t[2]]++] = static_cast<Index>(i);
    }
  }

  // Per-triangle geometry: area, volume, angles, degeneracy. The three angles of a triangle
  // share the sine term |u x v| = twice its area, so the angle at a corner is atan2(2A, u.v):
  // corners compare by their cotangent u.v / 2A without trigonometry, and only the extreme
  // corners get their atan2 at the end (degenerate triangles, 2A = 0, directly).
  double min_angle = 180, max_angle = 0;
  struct Corner {
    Vec u, v;
    double cot = 0;
  } smallest, largest;
  bool has_corner = false;
  for (const Triangle& t : mesh.triangles) {
    const Point &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    Vec ab = sub(b, a), ac = sub(c, a), bc_edge = sub(c, b);
    Vec n = cross(ab, ac);
    double twice_area = norm(n);
    m.area += 0.5 * twice_area;
    Vec pa{a[0], a[1], a[2]};
    Vec bc = cross(Vec{b[0], b[1], b[2]}, Vec{c[0], c[1], c[2]});
    m.volume += dot(pa, bc) / 6.0;
    bool repeated = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    if (repeated || twice_area == 0) m.degenerate_triangles++;
    // (Differences, not negations: -0.0 would turn atan2(0, 0) into 180 degrees.)
    Vec ba = sub(a, b), ca = sub(a, c), cb = sub(b, c);
    const Vec* corners[3][2] = {{&ab, &ac}, {&bc_edge, &ba}, {&ca, &cb}};
    if (twice_area == 0) {
      for (auto& [u, v] : corners) {
        double angle = angle_deg(*u, *v);
        min_angle = std::min(min_angle, angle);
        max_angle = std::max(max_angle, angle);
      }
      continue;
    }
    for (auto& [u, v] : corners) {
      double cot = dot(*u, *v) / twice_area;
      if (!has_corner || cot > smallest.cot) smallest = {*u, *v, cot};
      if (!has_corner || cot < largest.cot) largest = {*u, *v, cot};
      has_corner = true;
    }
  }
  if (has_corner) {
    min_angle = std::min(min_angle, angle_deg(smallest.u, smallest.v));
    max_angle = std::max(max_angle, angle_deg(largest.u, largest.v));
  }
  if (T > 0) {
    m.min_angle_deg = min_angle;
    m.max_angle_deg = max_angle;
  }

  UnionFind components(V), boundary(V);
  ParityUnionFind orientation(T);
  for (const Triangle& t : mesh.triangles) {
    components.unite(t[0], t[1]);
    components.unite(t[1], t[2]);
  }

  // Walk every vertex's triangles: its edges to higher-numbered neighbours (with how often and
  // in which direction triangles use them) and its fan (vertex manifoldness).
  struct Use {
    Index other;
    Index triangle;
    bool outgoing;  // the triangle runs v -> other
  };
  std::vector<Use> uses;
  std::vector<Index> link_nodes;
  std::vector<std::pair<Index, Index>> link_edges;
  double edge_length_sum = 0, instability_sum = 0;
  std::uint64_t instability_edges = 0;
  auto unit_normal = [&](Index ti, Vec& out) {
    const Triangle& t = mesh.triangles[ti];
    Vec n = cross(sub(mesh.positions[t[1]], mesh.positions[t[0]]),
                  sub(mesh.positions[t[2]], mesh.positions[t[0]]));
    double len = norm(n);
    if (len == 0) return false;
    out = {n[0] / len, n[1] / len, n[2] / len};
    return true;
  };
  for (std::size_t vi = 0; vi < V; ++vi) {
    const Index v = static_cast<Index>(vi);
    if (offsets[v] == offsets[v + 1]) {
      m.unreferenced_vertices++;
      continue;
    }
    uses.clear();
    link_edges.clear();
    bool vertex_ok = true;
    for (std::uint64_t k = offsets[v]; k < offsets[v + 1]; ++k) {
      Index ti = incident[k];
      const Triangle& t = mesh.triangles[ti];
      Index fan[2] = {0, 0};
      int fan_size = 0;
      for (int c = 0; c < 3; ++c) {
        if (t[c] != v) continue;
        Index next = t[(c + 1) % 3], prev = t[(c + 2) % 3];
        if (next != v) uses.push_back({next, ti, true});
        if (prev != v) uses.push_back({prev, ti, false});
        if (next != v && prev != v && next != prev) fan[0] = prev, fan[1] = next, fan_size = 2;
      }
      if (fan_size == 2) link_edges.emplace_back(fan[0], fan[1]);
      else vertex_ok = false;  // a triangle degenerate at v has no place in a disk
    }
    std::sort(uses.begin(), uses.end(), [](const Use& a, const Use& b) {
      return a.other != b.other ? a.other < b.other : a.triangle < b.triangle;
    });
    for (std::size_t i = 0; i < uses.size();) {
      std::size_t j = i;
      while (j < uses.size() && uses[j].other == uses[i].other) ++j;
      std::size_t count = j - i;
      if (count > 2) vertex_ok = false;
      if (uses[i].other > v) {
        Index w = uses[i].other;
        m.edges++;
        edge_length_sum += norm(sub(mesh.positions[w], mesh.positions[v]));
        if (count == 1) {
          m.boundary_edges++;
          boundary.unite(v, w);
        } else if (count > 2) {
          m.non_manifold_edges++;
        } else if (uses[i].triangle != uses[i + 1].triangle) {
          bool same_direction = uses[i].outgoing == uses[i + 1].outgoing;
          if (same_direction) m.inconsistent_edges++;
          if (!orientation.relate(uses[i].triangle, uses[i + 1].triangle, same_direction ? 1 : 0))
            m.is_orientable = false;
          Vec n1, n2;
          if (unit_normal(uses[i].triangle, n1) && unit_normal(uses[i + 1].triangle, n2)) {
            // Compare as consistently oriented faces: flip one when they disagree.
            double c = std::clamp(dot(n1, n2) * (same_direction ? -1.0 : 1.0), -1.0, 1.0);
            instability_sum += std::acos(c) * 180.0 / std::numbers::pi;
            instability_edges++;
          }
        }
      }
      i = j;
    }
    // The fan: the link edges (prev, next) of v's triangles must form one connected chain or
    // cycle. With every edge at v used at most twice, connectivity is what remains to check.
    if (vertex_ok && link_edges.size() > 1) {
      link_nodes.clear();
      for (auto& [a, b] : link_edges) link_nodes.push_back(a), link_nodes.push_back(b);
      std::sort(link_nodes.begin(), link_nodes.end());
      link_nodes.erase(std::unique(link_nodes.begin(), link_nodes.end()), link_nodes.end());
      std::vector<std::size_t> parent(link_nodes.size());
      for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
      auto find = [&](std::size_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
      };
      auto local = [&](Index x) {
        return static_cast<std::size_t>(std::lower_bound(link_nodes.begin(), link_nodes.end(), x) -
                                        link_nodes.begin());
      };
      std::size_t groups = link_nodes.size();
      for (auto& [a, b] : link_edges) {
        std::size_t ra = find(local(a)), rb = find(local(b));
        if (ra != rb) parent[ra] = rb, --groups;
      }
      if (groups != 1) vertex_ok = false;
    }
    if (!vertex_ok) m.non_manifold_vertices++;
  }

  // Components and boundary loops: distinct roots.
  std::vector<std::uint8_t> seen(V, 0);
  for (std::size_t v = 0; v < V; ++v) {
    if (offsets[v] == offsets[v + 1]) continue;
    Index root = components.find(static_cast<Index>(v));
    if (!(seen[root] & 1)) seen[root] |= 1, m.components++;
  }
  {
    // A vertex is on the boundary when some boundary edge was united with it; recount the
    // boundary vertices' roots (roots of isolated vertices are themselves, so skip those
    // without boundary edges by checking that their class has more than one member).
    std::vector<Index> boundary_size(V, 0);
    for (std::size_t v = 0; v < V; ++v) boundary_size[boundary.find(static_cast<Index>(v))]++;
    for (std::size_t v = 0; v < V; ++v)
      if (boundary.find(static_cast<Index>(v)) == v && boundary_size[v] > 1) m.boundary_loops++;
  }

  m.average_edge_length = m.edges ? edge_length_sum / double(m.edges) : 0;
  m.average_normal_instability = instability_edges ? instability_sum / double(instability_edges) : 0;
  m.is_manifold = m.non_manifold_edges == 0 && m.non_manifold_vertices == 0;
  m.is_oriented = m.inconsistent_edges == 0;
  m.is_watertight = T > 0 && m.boundary_edges == 0 && m.is_manifold;
  return m;
}

double measure_value(const Measures& m, const std::string& name) {
  if (name == "NumberOfVertices") return double(m.vertices);
  if (name == "NumberOfTriangles") return double(m.triangles);
  if (name == "NumberOfEdges") return double(m.edges);
  if (name == "NumberOfBoundaryLoops") return double(m.boundary_loops);
  if (name == "NumberOfComponents") return double(m.components);
  if (name == "MinimumAngle") return m.min_angle_deg;
  if (name == "MaximumAngle") return m.max_angle_deg;
  if (name == "AverageEdgeLength") return m.average_edge_length;
  if (name == "SurfaceArea") return m.area;
  if (name == "Volume") return m.volume;
  if (name == "AverageNormalInstability") return m.average_normal_instability;
  if (name == "IsManifold") return m.is_manifold;
  if (name == "IsOriented") return m.is_oriented;
  if (name == "IsOrientable") return m.is_orientable;
  if (name == "IsWatertight") return m.is_watertight;
  throw InvalidInput("unknown measure '" + name + "'");
}

std::string measures_to_json(const Measures& m) {
  std::string out = "{";
  bool first = true;
  for (const MeasureField& field : kMeasureFields) {
    double value = measure_value(m, field.name);
    out += first ? "" : ", ";
    first = false;
    out += "\"" + std::string(field.name) + "\": ";
    switch (field.type) {
      case ValueType::Natural: out += std::to_string(static_cast<std::uint64_t>(value)); break;
      case ValueType::Real: out += json_number(value); break;
      case ValueType::Boolean: out += value != 0 ? "true" : "false"; break;
    }
  }
  return out + "}";
}

}  // namespace meshflow::mesh
