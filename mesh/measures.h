#pragma once
// Topology and the analysis measures of DESIGN §5, correct on non-manifold input.
// Conventions (DESIGN §5): components are classes of triangles connected through shared
// vertices; boundary loops are connected components of the graph of boundary edges (edges
// used by exactly one triangle); an edge whose two ends are the same vertex (a face with a
// repeated index) is ignored for edges, boundaries and manifoldness, while its face still
// counts as a triangle.

#include <cstdint>
#include <string>

#include "mesh/mesh.h"

namespace meshflow::mesh {

struct Measures {
  // The 15 analysis operations of DESIGN §5 (names in comments).
  std::uint64_t vertices = 0;           // NumberOfVertices
  std::uint64_t triangles = 0;          // NumberOfTriangles
  std::uint64_t edges = 0;              // NumberOfEdges
  std::uint64_t boundary_loops = 0;     // NumberOfBoundaryLoops
  std::uint64_t components = 0;         // NumberOfComponents
  double min_angle_deg = 0;             // MinimumAngle
  double max_angle_deg = 0;             // MaximumAngle
  double average_edge_length = 0;       // AverageEdgeLength
  double area = 0;                      // SurfaceArea
  double volume = 0;                    // Volume
  // AverageNormalInstability: over the E2 edges used by exactly two triangles t1, t2 (both of
  // non-zero area), (1/E2) * sum acos(n1 . n2) in degrees, n1 and n2 their unit normals with
  // n2 flipped when the two traverse the edge the same way (so a consistent orientation is
  // compared): 0 on a plane, rising with noise, falling with smoothing.
  double average_normal_instability = 0;
  bool is_manifold = true;              // IsManifold (edge- and vertex-manifold)
  bool is_oriented = true;              // IsOriented
  bool is_orientable = true;            // IsOrientable
  bool is_watertight = false;           // IsWatertight

  // Details behind the booleans and counts, for `stats` and the tests.
  std::uint64_t boundary_edges = 0;
  std::uint64_t non_manifold_edges = 0;       // used by more than two triangles
  std::uint64_t non_manifold_vertices = 0;    // fan around the vertex is not one disk/half-disk
  std::uint64_t inconsistent_edges = 0;       // two triangles traverse it the same way
  std::uint64_t degenerate_triangles = 0;     // repeated index or zero area
  std::uint64_t unreferenced_vertices = 0;
};

// Every measure in one pass over the mesh. Memory beyond the mesh: a vertex->triangle
// incidence (4 B per corner + 8 B per vertex) and three union-finds, about 30 bytes per
// triangle on a closed mesh (V = T/2); `meshflow stats` peaks at 48 B/triangle with the mesh.
// Areas, volume and lengths are summed in double.
Measures compute_measures(const Mesh& mesh);

// Name of each analysis operation and its value as JSON text, in DESIGN §5's order; the
// single place the operation names of the measures are spelled.
enum class ValueType { Natural, Real, Boolean };
struct MeasureField {
  const char* name;
  ValueType type;
};
inline constexpr MeasureField kMeasureFields[] = {
    {"NumberOfVertices", ValueType::Natural},   {"NumberOfTriangles", ValueType::Natural},
    {"NumberOfEdges", ValueType::Natural},      {"NumberOfBoundaryLoops", ValueType::Natural},
    {"NumberOfComponents", ValueType::Natural}, {"MinimumAngle", ValueType::Real},
    {"MaximumAngle", ValueType::Real},          {"AverageEdgeLength", ValueType::Real},
    {"SurfaceArea", ValueType::Real},           {"Volume", ValueType::Real},
    {"AverageNormalInstability", ValueType::Real}, {"IsManifold", ValueType::Boolean},
    {"IsOriented", ValueType::Boolean},         {"IsOrientable", ValueType::Boolean},
    {"IsWatertight", ValueType::Boolean},
};

// The value of the measure named `name` as a double (booleans 0/1). \throws InvalidInput for
// an unknown name.
double measure_value(const Measures& measures, const std::string& name);

// `{"NumberOfVertices": 8, ...}`: naturals as integers, booleans as true/false, reals as
// numbers (never NaN).
std::string measures_to_json(const Measures& measures);

}  // namespace meshflow::mesh
