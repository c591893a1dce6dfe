#include "protocol/edit_mesh.h"

#include <algorithm>
#include <string>

#include "mesh/errors.h"

namespace meshflow::protocol {
namespace {

std::string edit_error(const char* what, Index id, const char* problem) {
  return std::string(what) + " " + std::to_string(id) + ": " + problem;
}

// Rotates t so that it starts with a and continues with b; false when (a, b) is not one of
// its directed edges.
bool rotate_to(mesh::Triangle t, Index a, Index b, Index& third) {
  for (int k = 0; k < 3; ++k)
    if (t[k] == a && t[(k + 1) % 3] == b) {
      third = t[(k + 2) % 3];
      return true;
    }
  return false;
}

}  // namespace

Point centre(const Point& a, const Point& b, const Point& c) {
  return {static_cast<float>((double(a[0]) + b[0] + c[0]) / 3.0),
          static_cast<float>((double(a[1]) + b[1] + c[1]) / 3.0),
          static_cast<float>((double(a[2]) + b[2] + c[2]) / 3.0)};
}

Point midpoint(const Point& a, const Point& b) {
  return {static_cast<float>((double(a[0]) + b[0]) / 2.0),
          static_cast<float>((double(a[1]) + b[1]) / 2.0),
          static_cast<float>((double(a[2]) + b[2]) / 2.0)};
}

EditMesh::EditMesh(const mesh::Mesh& base) : EditMesh(mesh::Mesh(base)) {}

EditMesh::EditMesh(mesh::Mesh&& base)
    : positions_(std::move(base.positions)),
      triangles_(std::move(base.triangles)),
      vertex_alive_(positions_.size(), true),
      triangle_alive_(triangles_.size(), true) {
  for (const auto& t : triangles_)
    for (Index v : t)
      if (v >= positions_.size()) throw InvalidInput("base mesh has a vertex index out of range");
}

void EditMesh::check_vertex(Index v, const char* what) const {
  if (v >= positions_.size()) throw InvalidInput(edit_error(what, v, "vertex id out of range"));
  if (!vertex_alive_[v]) throw InvalidInput(edit_error(what, v, "vertex was removed"));
}

void EditMesh::check_triangle(Index t, const char* what) const {
  if (t >= triangles_.size()) throw InvalidInput(edit_error(what, t, "triangle id out of range"));
  if (!triangle_alive_[t]) throw InvalidInput(edit_error(what, t, "triangle was removed"));
}

void EditMesh::ensure_incidence() {
  if (has_incidence_) return;
  incidence_.assign(positions_.size(), {});
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    if (!triangle_alive_[t]) continue;
    const auto& tri = triangles_[t];
    for (int k = 0; k < 3; ++k)
      if (k == 0 || (tri[k] != tri[0] && (k == 1 || tri[k] != tri[1])))
        incidence_[tri[k]].push_back(static_cast<Index>(t));
  }
  has_incidence_ = true;
}

const std::vector<Index>& EditMesh::triangles_of(Index v) {
  ensure_incidence();
  return incidence_[v];
}

std::vector<Index> EditMesh::triangles_of_edge(Index a, Index b) {
  ensure_incidence();
  std::vector<Index> out;
  for (Index t : incidence_[a]) {
    const auto& tri = triangles_[t];
    if (tri[0] == b || tri[1] == b || tri[2] == b) out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Index EditMesh::push_vertex(const Point& p) {
  positions_.push_back(p);
  vertex_alive_.push_back(true);
  if (has_incidence_) incidence_.emplace_back();
  return static_cast<Index>(positions_.size() - 1);
}

Index EditMesh::push_triangle(const mesh::Triangle& tri) {
  Index t = static_cast<Index>(triangles_.size());
  triangles_.push_back(tri);
  triangle_alive_.push_back(true);
  if (has_incidence_)
    for (int k = 0; k < 3; ++k)
      if (k == 0 || (tri[k] != tri[0] && (k == 1 || tri[k] != tri[1]))) incidence_[tri[k]].push_back(t);
  return t;
}

void EditMesh::kill_triangle(Index t) {
  triangle_alive_[t] = false;
  if (!has_incidence_) return;
  for (Index v : triangles_[t]) {
    auto& list = incidence_[v];
    list.erase(std::remove(list.begin(), list.end(), t), list.end());
  }
}

void EditMesh::apply_unrecorded(const Edit& edit) {
  std::visit(
      [this](const auto& e) {
        using E = std::decay_t<decltype(e)>;
        if constexpr (std::is_same_v<E, AddTriangle>) {
          check_vertex(e.a, "AddTriangle");
          check_vertex(e.b, "AddTriangle");
          check_vertex(e.c, "AddTriangle");
          push_triangle({e.a, e.b, e.c});
        } else if constexpr (std::is_same_v<E, RemoveTriangle>) {
          check_triangle(e.t, "RemoveTriangle");
          kill_triangle(e.t);
        } else if constexpr (std::is_same_v<E, SplitTriangle>) {
          check_triangle(e.t, "SplitTriangle");
          auto [a, b, c] = triangles_[e.t];
          Point p = e.p ? *e.p : centre(positions_[a], positions_[b], positions_[c]);
          kill_triangle(e.t);
          Index m = push_vertex(p);
          push_triangle({a, b, m});
          push_triangle({b, c, m});
          push_triangle({c, a, m});
        } else if constexpr (std::is_same_v<E, AddVertex>) {
          push_vertex(e.p);
        } else if constexpr (std::is_same_v<E, RemoveVertex>) {
          check_vertex(e.v, "RemoveVertex");
          ensure_incidence();
          if (!incidence_[e.v].empty())
            throw InvalidInput(edit_error("RemoveVertex", e.v, "vertex is still used by a triangle"));
          vertex_alive_[e.v] = false;
        } else if constexpr (std::is_same_v<E, MoveVertex>) {
          check_vertex(e.v, "MoveVertex");
          positions_[e.v] = e.p;
        } else if constexpr (std::is_same_v<E, MoveAllVertices>) {
          std::size_t live = std::count(vertex_alive_.begin(), vertex_alive_.end(), true);
          if (e.positions.size() != live)
            throw InvalidInput("MoveAllVertices: " + std::to_string(e.positions.size()) +
                               " positions for " + std::to_string(live) + " live vertices");
          std::size_t k = 0;
          for (std::size_t v = 0; v < positions_.size(); ++v)
            if (vertex_alive_[v]) positions_[v] = e.positions[k++];
        } else if constexpr (std::is_same_v<E, AddEdge> || std::is_same_v<E, SwapEdge>) {
          const char* name = std::is_same_v<E, AddEdge> ? "AddEdge" : "SwapEdge";
          check_vertex(e.a, name);
          check_vertex(e.b, name);
          Index x = e.a, y = e.b;
          if constexpr (std::is_same_v<E, AddEdge>) {
            // Find the edge (x, y) whose two triangles have a and b as opposite corners.
            bool found = false;
            for (Index t : triangles_of(e.a)) {
              const auto& tri = triangles_[t];
              for (int k = 0; k < 3 && !found; ++k) {
                if (tri[k] != e.a) continue;
                Index p = tri[(k + 1) % 3], q = tri[(k + 2) % 3];
                auto shared = triangles_of_edge(p, q);
                for (Index s : shared) {
                  const auto& o = triangles_[s];
                  if (s != t && (o[0] == e.b || o[1] == e.b || o[2] == e.b)) {
                    x = std::min(p, q), y = std::max(p, q), found = true;
                    break;
                  }
                }
              }
              if (found) break;
            }
            if (!found) throw InvalidInput("AddEdge " + std::to_string(e.a) + "-" + std::to_string(e.b) +
                                           ": not opposite corners of two triangles sharing an edge");
          }
          auto tris = triangles_of_edge(x, y);
          if (tris.size() != 2)
            throw InvalidInput(std::string(name) + " " + std::to_string(x) + "-" + std::to_string(y) +
                               ": the edge has " + std::to_string(tris.size()) + " triangles, expected 2");
          Index c = 0, d = 0, t1 = tris[0], t2 = tris[1];
          if (!rotate_to(triangles_[t1], x, y, c)) std::swap(t1, t2);
          if (!rotate_to(triangles_[t1], x, y, c) || !rotate_to(triangles_[t2], y, x, d))
            throw InvalidInput(std::string(name) + ": the two triangles of the edge are not consistently oriented");
          if (c == d) throw InvalidInput(std::string(name) + ": the edge's opposite corners coincide");
          kill_triangle(t1);
          kill_triangle(t2);
          push_triangle({x, d, c});
          push_triangle({d, y, c});
        } else if constexpr (std::is_same_v<E, CollapseEdge>) {
          check_vertex(e.a, "CollapseEdge");
          check_vertex(e.b, "CollapseEdge");
          if (e.a == e.b) throw InvalidInput("CollapseEdge: both ends are vertex " + std::to_string(e.a));
          for (Index t : triangles_of_edge(e.a, e.b)) kill_triangle(t);
          std::vector<Index> moved = incidence_[e.b];
          for (Index t : moved) {
            for (Index& v : triangles_[t])
              if (v == e.b) v = e.a;
            incidence_[e.a].push_back(t);
          }
          incidence_[e.b].clear();
          auto& list = incidence_[e.a];
          std::sort(list.begin(), list.end());
          list.erase(std::unique(list.begin(), list.end()), list.end());
          vertex_alive_[e.b] = false;
          if (e.p) positions_[e.a] = *e.p;
        } else if constexpr (std::is_same_v<E, SplitEdge>) {
          check_vertex(e.a, "SplitEdge");
          check_vertex(e.b, "SplitEdge");
          auto tris = triangles_of_edge(e.a, e.b);
          if (tris.empty()) throw InvalidInput("SplitEdge " + std::to_string(e.a) + "-" + std::to_string(e.b) + ": no such edge");
          Index m = push_vertex(e.p ? *e.p : midpoint(positions_[e.a], positions_[e.b]));
          for (Index t : tris) {
            mesh::Triangle tri = triangles_[t];
            Index c = 0;
            kill_triangle(t);
            if (rotate_to(tri, e.a, e.b, c)) {
              push_triangle({e.a, m, c});
              push_triangle({m, e.b, c});
            } else if (rotate_to(tri, e.b, e.a, c)) {
              push_triangle({e.b, m, c});
              push_triangle({m, e.a, c});
            } else {
              throw InvalidInput("SplitEdge: a triangle of the edge is degenerate");
            }
          }
        } else if constexpr (std::is_same_v<E, ClearAll>) {
          std::fill(vertex_alive_.begin(), vertex_alive_.end(), false);
          std::fill(triangle_alive_.begin(), triangle_alive_.end(), false);
          if (has_incidence_)
            for (auto& list : incidence_) list.clear();
        }
      },
      edit);
}

void EditMesh::apply(const Edit& edit, std::size_t index) {
  try {
    apply_unrecorded(edit);
  } catch (const InvalidInput& e) {
    throw InvalidInput("edit " + std::to_string(index) + ": " + e.what());
  }
  edits_.push_back(edit);
}

Index EditMesh::add_triangle(Index a, Index b, Index c) {
  apply(AddTriangle{a, b, c}, edits_.size());
  return static_cast<Index>(triangles_.size() - 1);
}
void EditMesh::remove_triangle(Index t) { apply(RemoveTriangle{t}, edits_.size()); }
Index EditMesh::split_triangle(Index t, std::optional<Point> p) {
  apply(SplitTriangle{t, p}, edits_.size());
  return static_cast<Index>(positions_.size() - 1);
}
Index EditMesh::add_vertex(Point p) {
  apply(AddVertex{p}, edits_.size());
  return static_cast<Index>(positions_.size() - 1);
}
void EditMesh::remove_vertex(Index v) { apply(RemoveVertex{v}, edits_.size()); }
void EditMesh::move_vertex(Index v, Point p) { apply(MoveVertex{v, p}, edits_.size()); }
void EditMesh::move_all_vertices(std::vector<Point> positions) {
  apply(MoveAllVertices{std::move(positions)}, edits_.size());
}
void EditMesh::add_edge(Index a, Index b) { apply(AddEdge{a, b}, edits_.size()); }
void EditMesh::swap_edge(Index a, Index b) { apply(SwapEdge{a, b}, edits_.size()); }
void EditMesh::collapse_edge(Index a, Index b, std::optional<Point> p) {
  ensure_incidence();
  apply(CollapseEdge{a, b, p}, edits_.size());
}
Index EditMesh::split_edge(Index a, Index b, std::optional<Point> p) {
  apply(SplitEdge{a, b, p}, edits_.size());
  return static_cast<Index>(positions_.size() - 1);
}
void EditMesh::clear_all() { apply(ClearAll{}, edits_.size()); }

mesh::Mesh EditMesh::compact() const {
  mesh::Mesh out;
  std::vector<Index> renumber(positions_.size(), 0);
  for (std::size_t v = 0; v < positions_.size(); ++v) {
    if (!vertex_alive_[v]) continue;
    renumber[v] = static_cast<Index>(out.positions.size());
    out.positions.push_back(positions_[v]);
  }
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    if (!triangle_alive_[t]) continue;
    const auto& tri = triangles_[t];
    for (Index v : tri)
      if (!vertex_alive_[v]) throw InvalidInput("a live triangle uses removed vertex " + std::to_string(v));
    out.triangles.push_back({renumber[tri[0]], renumber[tri[1]], renumber[tri[2]]});
  }
  return out;
}

mesh::Mesh apply_edits(const mesh::Mesh& base, const EditList& edits) {
  EditMesh mesh(base);
  for (std::size_t i = 0; i < edits.size(); ++i) mesh.apply(edits[i], i);
  return mesh.compact();
}

}  // namespace meshflow::protocol
