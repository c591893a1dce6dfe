#pragma once
// The local repair operations of DESIGN §5 (thesis Appendix A). Each edits through a
// protocol::EditMesh, so its correction is the list of edits it made.

#include <atomic>
#include <cstdint>

#include "mesh/mesh.h"
#include "protocol/edit_mesh.h"

namespace meshflow::services {

// Keeps the largest connected component (triangles connected through shared vertices; ties go
// to the component with the lowest vertex id); removes the other triangles and every vertex not
// used by the kept component.
void remove_smallest_components(protocol::EditMesh& mesh);

// Uniform umbrella (Laplacian) smoothing: each iteration moves every interior vertex to the
// average of its edge neighbours (Jacobi: all from the previous positions). Boundary vertices
// (on an edge used by one triangle) and unreferenced vertices do not move, so holes keep their
// rims and the surface does not shrink from its border. One MoveAllVertices edit.
// \throws std::runtime_error("cancelled") when `cancel` turns true (checked every iteration;
// the mesh is then left as it was).
void laplacian_smoothing(protocol::EditMesh& mesh, int iterations, const std::atomic<bool>* cancel = nullptr);

// Moves every vertex along its area-weighted normal by a uniform random distance in
// [-max_distance, max_distance] (absolute). Reproducible: mt19937_64 seeded with `seed`, one
// draw per vertex in id order, mapped to [0,1) by its top 53 bits. One MoveAllVertices edit.
void add_noise(protocol::EditMesh& mesh, double max_distance, std::uint64_t seed);

// Removes zero-area triangles by local edits, decided with exact predicates: a triangle with a
// zero-length edge (repeated vertex or coincident points) collapses that edge; a collinear
// triangle flips its longest edge into the neighbour across it (or, on the boundary, is removed:
// its two short edges already span the same segment). Of triangles with the same vertex set,
// one stays, or none when that opens fewer boundary edges (a triangle doubled back on itself,
// hanging from one edge). Repeats until no zero-area triangle is left (or no edit helps).
void remove_degenerate_triangles(protocol::EditMesh& mesh);

// Fills boundary loops (Liepa: triangulate, refine, fair; CGAL), all of them or all but the one
// with the most edges. Adds vertices and triangles: the patches' triangles in depth-first order,
// their new vertices in the order those triangles first use them (what corrections code best).
void fill_holes(protocol::EditMesh& mesh, bool keep_largest_loop);

}  // namespace meshflow::services
