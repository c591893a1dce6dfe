// The only translation unit that includes CGAL (see cgal_bridge.h).
#include "services/cgal_bridge.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <map>
#include <random>

namespace meshflow::services::cgal {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<P3>;
namespace PMP = CGAL::Polygon_mesh_processing;

P3 to_cgal(const Point& p) { return P3(p[0], p[1], p[2]); }

std::uint64_t edge_key(Index a, Index b) { return std::uint64_t{std::min(a, b)} << 32 | std::max(a, b); }

}  // namespace

bool collinear(const Point& a, const Point& b, const Point& c) {
  return CGAL::collinear(to_cgal(a), to_cgal(b), to_cgal(c));
}

HoleFill fill_holes(const mesh::Mesh& input, bool skip_largest, std::span<const std::uint64_t> boundary_edges) {
  HoleFill out;
  // The referenced vertices as a polygon soup (point i of the soup = vertex soup_to_mesh[i]).
  std::vector<P3> points;
  std::vector<Index> soup_to_mesh;
  std::vector<std::int64_t> mesh_to_soup(input.positions.size(), -1);
  std::vector<std::vector<std::size_t>> polygons;
  for (const auto& t : input.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    std::vector<std::size_t> polygon;
    for (Index v : t) {
      if (mesh_to_soup[v] < 0) {
        mesh_to_soup[v] = static_cast<std::int64_t>(points.size());
        points.push_back(to_cgal(input.positions[v]));
        soup_to_mesh.push_back(v);
      }
      polygon.push_back(static_cast<std::size_t>(mesh_to_soup[v]));
    }
    polygons.push_back(std::move(polygon));
  }
  // Non-manifold vertices are duplicated by orient_polygon_soup (appended points); the visitor
  // says which vertex each copy comes from. (Matching copies by position would send a copy to
  // another vertex at the same place: scans have such unwelded twins.)
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    struct DuplicationVisitor : PMP::Default_orientation_visitor {
      std::vector<Index>* soup_to_mesh;
      void duplicated_vertex(std::size_t original, std::size_t copy) {
        if (soup_to_mesh->size() <= copy) soup_to_mesh->resize(copy + 1);
        (*soup_to_mesh)[copy] = (*soup_to_mesh)[original];
      }
    } visitor;
    visitor.soup_to_mesh = &soup_to_mesh;
    PMP::orient_polygon_soup(points, polygons, CGAL::parameters::visitor(visitor));
  }
  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  std::size_t soup_vertices = sm.number_of_vertices();

  // Edges used by exactly one triangle of the input. Where the soup had to be cut (at
  // non-manifold or unorientable edges) the halfedge copy has border cycles along edges that
  // are no boundary at all; a cycle with no boundary edge is such a cut, not a hole. When the
  // input is a neighbourhood cut out of a larger mesh, `boundary_edges` names the true
  // boundary, and a cycle through an edge of the cut (one triangle here, more there) is no hole.
  std::vector<std::uint64_t> edge_keys;
  for (const auto& polygon : polygons)
    for (std::size_t k = 0; k < 3; ++k) {
      Index a = soup_to_mesh[polygon[k]], b = soup_to_mesh[polygon[(k + 1) % 3]];
      edge_keys.push_back(edge_key(a, b));
    }
  std::sort(edge_keys.begin(), edge_keys.end());
  auto uses = [&](Index a, Index b) {
    auto [first, last] = std::equal_range(edge_keys.begin(), edge_keys.end(), edge_key(a, b));
    return last - first;
  };
  auto is_true_boundary = [&](Index a, Index b) {
    if (boundary_edges.empty()) return uses(a, b) == 1;
    return std::binary_search(boundary_edges.begin(), boundary_edges.end(), edge_key(a, b));
  };

  // One border halfedge per hole, with its length in edges.
  std::vector<std::pair<std::size_t, SurfaceMesh::Halfedge_index>> holes;
  std::vector<bool> visited(sm.number_of_halfedges(), false);
  for (auto h : sm.halfedges()) {
    if (!sm.is_border(h) || visited[h.idx()]) continue;
    std::size_t length = 0;
    bool has_boundary = false, has_cut = false;
    for (auto g : CGAL::halfedges_around_face(h, sm)) {
      visited[g.idx()] = true, ++length;
      Index a = soup_to_mesh[sm.source(g).idx()], b = soup_to_mesh[sm.target(g).idx()];
      bool boundary = is_true_boundary(a, b);
      has_boundary = has_boundary || boundary;
      has_cut = has_cut || (!boundary && uses(a, b) == 1);
    }
    if (has_boundary && !has_cut) holes.emplace_back(length, h);
  }
  if (skip_largest && !holes.empty()) {
    auto largest = std::max_element(holes.begin(), holes.end(),
                                    [](auto& x, auto& y) { return x.first < y.first; });
    holes.erase(largest);
  }
  std::vector<SurfaceMesh::Face_index> new_faces;
  std::vector<mesh::Triangle> loop_patches;  // mesh ids, for loops CGAL could not fill in place
  for (auto& [length, h] : holes) {
    std::vector<SurfaceMesh::Face_index> faces;
    std::vector<SurfaceMesh::Vertex_index> vertices;
    bool fair_ok = std::get<0>(PMP::triangulate_refine_and_fair_hole(
        sm, h, std::back_inserter(faces), std::back_inserter(vertices)));
    if (!fair_ok && faces.empty())
      PMP::triangulate_and_refine_hole(sm, h, std::back_inserter(faces), std::back_inserter(vertices));
    if (faces.empty()) PMP::triangulate_hole(sm, h, std::back_inserter(faces));
    if (faces.empty()) {
      // Every triangulation inside the mesh would repeat an edge it already has (loops of
      // unwelded or pinched input): triangulate the loop as a polyline, outside the halfedge
      // copy; the patch then shares those edges, as non-manifold input may.
      std::vector<P3> polyline;
      std::vector<Index> loop;
      for (auto g : CGAL::halfedges_around_face(h, sm)) {
        polyline.push_back(sm.point(sm.source(g)));
        loop.push_back(soup_to_mesh[sm.source(g).idx()]);
      }
      std::vector<CGAL::Triple<int, int, int>> patch;
      PMP::triangulate_hole_polyline(polyline, std::back_inserter(patch));
      for (const auto& t : patch) {
        mesh::Triangle tri{loop[t.first], loop[t.second], loop[t.third]};
        if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]) loop_patches.push_back(tri);
      }
    }
    new_faces.insert(new_faces.end(), faces.begin(), faces.end());
  }
  // New vertices of the patches, in creation order, after the mesh's.
  std::map<std::size_t, Index> new_vertex_id;
  for (auto v : sm.vertices()) {
    if (v.idx() < soup_vertices) continue;
    const P3& p = sm.point(v);
    new_vertex_id[v.idx()] = static_cast<Index>(input.positions.size() + out.vertices.size());
    out.vertices.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
  }
  for (auto f : new_faces) {
    mesh::Triangle t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
      if (k == 3) break;
      t[k++] = v.idx() < soup_vertices ? soup_to_mesh[v.idx()] : new_vertex_id.at(v.idx());
    }
    if (k == 3) out.triangles.push_back(t);
  }
  out.triangles.insert(out.triangles.end(), loop_patches.begin(), loop_patches.end());
  return out;
}

Distance surface_distance(const mesh::Mesh& a, const mesh::Mesh& b, std::size_t samples_a,
                          std::size_t samples_b, std::uint64_t seed) {
  using Triangle3 = Kernel::Triangle_3;
  using Iterator = std::vector<Triangle3>::const_iterator;
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

  auto triangles_of = [](const mesh::Mesh& m) {
    std::vector<Triangle3> out;
    out.reserve(m.triangles.size());
    for (const auto& t : m.triangles) {
      Triangle3 tri(to_cgal(m.positions[t[0]]), to_cgal(m.positions[t[1]]), to_cgal(m.positions[t[2]]));
      if (!tri.is_degenerate()) out.push_back(tri);
    }
    return out;
  };
  // Mean and max distance from `count` area-uniform samples of `from` to the surface of `to`.
  auto one_way = [&](const std::vector<Triangle3>& from, const std::vector<Triangle3>& to,
                     std::size_t count, std::uint64_t s, double& mean, double& max) {
    mean = max = 0;
    if (from.empty() || to.empty()) return;
    Tree tree(to.begin(), to.end());
    tree.accelerate_distance_queries();
    std::vector<double> cumulative(from.size());
    double total = 0;
    for (std::size_t i = 0; i < from.size(); ++i) cumulative[i] = total += std::sqrt(from[i].squared_area());
    std::mt19937_64 rng(s);
    auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
    double sum = 0;
    for (std::size_t k = 0; k < count; ++k) {
      // Stratified over the area so that every triangle gets its share.
      double target = (static_cast<double>(k) + uniform()) / static_cast<double>(count) * total;
      std::size_t i = std::min<std::size_t>(
          std::lower_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin(), from.size() - 1);
      double r1 = uniform(), r2 = uniform();
      if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
      const Triangle3& t = from[i];
      P3 p = t[0] + r1 * (t[1] - t[0]) + r2 * (t[2] - t[0]);
      double d = std::sqrt(tree.squared_distance(p));
      sum += d;
      max = std::max(max, d);
    }
    mean = sum / static_cast<double>(count);
  };
  std::vector<Triangle3> ta = triangles_of(a), tb = triangles_of(b);
  Distance d;
  one_way(ta, tb, samples_a, seed, d.mean_ab, d.max_ab);
  one_way(tb, ta, samples_b, seed + 1, d.mean_ba, d.max_ba);
  return d;
}

struct DistanceToSurface::Tree {
  using Triangle3 = Kernel::Triangle_3;
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle3>::const_iterator>;
  std::vector<Triangle3> triangles;
  CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>> aabb;
};

DistanceToSurface::DistanceToSurface(const mesh::Mesh& surface) : tree_(std::make_unique<Tree>()) {
  for (const auto& t : surface.triangles) {
    Tree::Triangle3 tri(to_cgal(surface.positions[t[0]]), to_cgal(surface.positions[t[1]]), to_cgal(surface.positions[t[2]]));
    if (!tri.is_degenerate()) tree_->triangles.push_back(tri);
  }
  tree_->aabb.insert(tree_->triangles.begin(), tree_->triangles.end());
  tree_->aabb.accelerate_distance_queries();
}

DistanceToSurface::~DistanceToSurface() = default;

double DistanceToSurface::operator()(const Point& p) const {
  return tree_->triangles.empty() ? 0.0 : std::sqrt(tree_->aabb.squared_distance(to_cgal(p)));
}

}  // namespace meshflow::services::cgal
