// Peer for bench/simplify_bench.sh: CGAL's edge_collapse with Garland-Heckbert plane policies
// (CGAL 5.5), stopping at an edge count (3 per target vertex). Usage: cgal_simplify IN OUT TARGET_VERTICES
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cstdio>
#include <string>

#include "mesh/mesh_io.h"

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMS = CGAL::Surface_mesh_simplification;

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: cgal_simplify IN OUT TARGET_VERTICES\n");
    return 2;
  }
  meshflow::mesh::Mesh in = meshflow::mesh::read_mesh(argv[1]);
  std::vector<Kernel::Point_3> points;
  for (auto& p : in.positions) points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> polygons;
  for (auto& t : in.triangles)
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) polygons.push_back({t[0], t[1], t[2]});
  if (!CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polygons))
    CGAL::Polygon_mesh_processing::orient_polygon_soup(points, polygons);
  SurfaceMesh sm;
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, sm);
  // CGAL 5.5 counts edges: about 3 per vertex on a closed surface.
  std::size_t target_edges = 3 * std::stoul(argv[3]);
  SMS::Count_stop_predicate<SurfaceMesh> stop(target_edges);
  SMS::GarlandHeckbert_plane_policies<SurfaceMesh, Kernel> policies(sm);
  SMS::edge_collapse(sm, stop, CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
  sm.collect_garbage();
  meshflow::mesh::Mesh out;
  for (auto v : sm.vertices()) {
    auto& p = sm.point(v);
    out.positions.push_back({float(p.x()), float(p.y()), float(p.z())});
  }
  for (auto f : sm.faces()) {
    meshflow::mesh::Triangle t{};
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) t[k++] = static_cast<meshflow::mesh::Index>(v.idx());
    out.triangles.push_back(t);
  }
  meshflow::mesh::write_mesh(out, argv[2]);
  return 0;
}
