#pragma once
// A mesh under edit (DESIGN §6): the base mesh plus appended slots and live flags. Every edit
// of protocol/edits.h is applied with the exact semantics written there and appended to the
// mesh's edit list, so an operation that edits through an EditMesh gets its correction for
// free, and a receiver that applies the same list gets the same compact() bit for bit.

#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "protocol/edits.h"

namespace meshflow::protocol {

class EditMesh {
 public:
  explicit EditMesh(const mesh::Mesh& base);
  explicit EditMesh(mesh::Mesh&& base);

  // Each applies one edit and records it. \throws InvalidInput when the edit does not fit the
  // mesh (dead or out-of-range ids, an edge without the triangles it needs); nothing changes
  // then.
  Index add_triangle(Index a, Index b, Index c);
  void remove_triangle(Index t);
  Index split_triangle(Index t, std::optional<Point> p = std::nullopt);  // returns the new vertex
  Index add_vertex(Point p);
  void remove_vertex(Index v);
  void move_vertex(Index v, Point p);
  void move_all_vertices(std::vector<Point> positions);  // live vertices, ascending id order
  void add_edge(Index a, Index b);
  void swap_edge(Index a, Index b);
  void collapse_edge(Index a, Index b, std::optional<Point> p = std::nullopt);
  Index split_edge(Index a, Index b, std::optional<Point> p = std::nullopt);
  void clear_all();

  // Applies (and records) an edit from a correction; `index` names it in error messages.
  void apply(const Edit& edit, std::size_t index = 0);

  // Live vertices and triangles in ascending id order, renumbered (DESIGN §6).
  mesh::Mesh compact() const;

  const EditList& edits() const { return edits_; }
  EditList take_edits() { return std::move(edits_); }

  std::size_t vertex_slots() const { return positions_.size(); }
  std::size_t triangle_slots() const { return triangles_.size(); }
  bool vertex_alive(Index v) const { return v < vertex_alive_.size() && vertex_alive_[v]; }
  bool triangle_alive(Index t) const { return t < triangle_alive_.size() && triangle_alive_[t]; }
  const Point& position(Index v) const { return positions_[v]; }
  const mesh::Triangle& triangle(Index t) const { return triangles_[t]; }
  // Live triangles using vertex v (builds the incidence on first use, then keeps it current).
  const std::vector<Index>& triangles_of(Index v);
  // Live triangles containing both a and b, ascending.
  std::vector<Index> triangles_of_edge(Index a, Index b);

 private:
  void apply_unrecorded(const Edit& edit);
  void check_vertex(Index v, const char* what) const;
  void check_triangle(Index t, const char* what) const;
  Index push_triangle(const mesh::Triangle& t);
  Index push_vertex(const Point& p);
  void kill_triangle(Index t);
  void ensure_incidence();

  std::vector<Point> positions_;
  std::vector<mesh::Triangle> triangles_;
  std::vector<bool> vertex_alive_;
  std::vector<bool> triangle_alive_;
  std::vector<std::vector<Index>> incidence_;  // empty until needed
  bool has_incidence_ = false;
  EditList edits_;
};

// The result of applying `edits` to `base`, compacted. \throws InvalidInput.
mesh::Mesh apply_edits(const mesh::Mesh& base, const EditList& edits);

// A point computed by an edit: double arithmetic on float32 inputs, rounded once.
Point centre(const Point& a, const Point& b, const Point& c);
Point midpoint(const Point& a, const Point& b);

}  // namespace meshflow::protocol
