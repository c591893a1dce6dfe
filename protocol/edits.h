#pragma once
// The edit operations of a correction (thesis Appendix B, DESIGN §6): what an atomic
// operation did to its input. Applying a list of edits to the base mesh is deterministic, so
// a receiver reproduces the producer's output bit for bit.
//
// Semantics (all ids are positions in the mesh being edited, 0-based):
//  - The mesh under edit keeps every vertex and triangle slot it ever had; additions append
//    (a new vertex gets id = current vertex slot count, likewise triangles); removals only
//    mark a slot dead. Compaction (when the result is serialized) keeps the live vertices and
//    triangles in ascending id order and renumbers the triangles' vertex ids accordingly.
//  - Positions are float32. Any point an edit computes (a triangle's centre, an edge's
//    midpoint) is computed in double from the float32 corners and rounded to float32 once.
//  - An edge is named by its two vertex ids (a, b); "the triangles of edge (a, b)" are the
//    live triangles containing both, in ascending id order.
//
//  AddTriangle{a,b,c}        append triangle (a, b, c).
//  RemoveTriangle{t}         mark triangle t dead.
//  SplitTriangle{t[,p]}      t = (a,b,c) dead; append vertex m = p or the centre of t; append
//                            (a,b,m), (b,c,m), (c,a,m).
//  AddVertex{p}              append a vertex at p.
//  RemoveVertex{v}           mark vertex v dead (no live triangle may use it).
//  MoveVertex{v,p}           position of v := p.
//  MoveAllVertices{ps}       positions of the live vertices, in ascending id order, := ps.
//  AddEdge{a,b}              a and b are the opposite corners of two live triangles sharing
//                            an edge (x,y): that edge is swapped so that a-b becomes one
//                            (same result as SwapEdge{x,y}).
//  SwapEdge{a,b}             the edge (a,b) has exactly two triangles t1 = (a,b,c) and
//                            t2 = (b,a,d) (up to rotation): both dead; append (a,d,c) and
//                            (d,b,c), so c-d is the new edge and orientation is kept.
//  CollapseEdge{a,b[,p]}     b merges into a: triangles of edge (a,b) dead; every other live
//                            triangle using b uses a instead (same id, same corner); b dead;
//                            a moves to p when given (else stays).
//  SplitEdge{a,b[,p]}        append vertex m = p or the midpoint of (a,b); each triangle of
//                            edge (a,b), in ascending id order, (a,b,c) up to rotation, dead;
//                            append (a,m,c), (m,b,c) with the triangle's own orientation.
//  ClearAll                  every vertex and triangle dead.
//
// Every edit is checked when applied (ids in range and live, edges with the triangles they
// need); a violation throws InvalidInput naming the edit's index in the list.

#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::protocol {

using mesh::Index;
using mesh::Point;

struct AddTriangle { Index a, b, c; };
struct RemoveTriangle { Index t; };
struct SplitTriangle { Index t; std::optional<Point> p; };
struct AddVertex { Point p; };
struct RemoveVertex { Index v; };
struct MoveVertex { Index v; Point p; };
struct MoveAllVertices { std::vector<Point> positions; };
struct AddEdge { Index a, b; };
struct SwapEdge { Index a, b; };
struct CollapseEdge { Index a, b; std::optional<Point> p; };
struct SplitEdge { Index a, b; std::optional<Point> p; };
struct ClearAll {};

using Edit = std::variant<AddTriangle, RemoveTriangle, SplitTriangle, AddVertex, RemoveVertex,
                          MoveVertex, MoveAllVertices, AddEdge, SwapEdge, CollapseEdge, SplitEdge,
                          ClearAll>;
using EditList = std::vector<Edit>;

}  // namespace meshflow::protocol
