#include "protocol/diff.h"

#include <algorithm>

#include "protocol/edit_mesh.h"

namespace meshflow::protocol {
namespace {

EditList rebuild(const mesh::Mesh& b) {
  EditList edits{ClearAll{}};
  return edits;
}

EditList clear_and_add(const mesh::Mesh& a, const mesh::Mesh& b) {
  EditList edits = rebuild(b);
  auto base = static_cast<Index>(a.positions.size());
  for (const Point& p : b.positions) edits.push_back(AddVertex{p});
  for (const auto& t : b.triangles) edits.push_back(AddTriangle{base + t[0], base + t[1], base + t[2]});
  return edits;
}

}  // namespace

EditList diff_meshes(const mesh::Mesh& a, const mesh::Mesh& b) {
  EditList edits;
  // Same connectivity, moved vertices: moves only.
  if (a.positions.size() == b.positions.size() && a.triangles == b.triangles) {
    std::size_t moved = 0;
    for (std::size_t v = 0; v < a.positions.size(); ++v) moved += a.positions[v] != b.positions[v];
    if (moved * 4 > a.positions.size()) {
      edits.push_back(MoveAllVertices{b.positions});
    } else {
      for (std::size_t v = 0; v < a.positions.size(); ++v)
        if (a.positions[v] != b.positions[v]) edits.push_back(MoveVertex{static_cast<Index>(v), b.positions[v]});
    }
    return edits;
  }
  // Vertices: b = (a's vertices kept in order, same positions) + (new vertices).
  std::vector<Index> b_to_a(b.positions.size(), 0);
  std::vector<bool> a_kept(a.positions.size(), false);
  std::size_t j = 0;
  for (std::size_t i = 0; i < a.positions.size() && j < b.positions.size(); ++i)
    if (a.positions[i] == b.positions[j]) {
      a_kept[i] = true;
      b_to_a[j++] = static_cast<Index>(i);
    }
  std::size_t kept_vertices = j;
  for (std::size_t k = kept_vertices; k < b.positions.size(); ++k)
    b_to_a[k] = static_cast<Index>(a.positions.size() + (k - kept_vertices));
  // Triangles: b = (a's triangles kept in order) + (new triangles), after renumbering.
  std::vector<bool> t_kept(a.triangles.size(), false);
  std::size_t tj = 0;
  for (std::size_t i = 0; i < a.triangles.size() && tj < b.triangles.size(); ++i) {
    const auto& tb = b.triangles[tj];
    mesh::Triangle mapped{b_to_a[tb[0]], b_to_a[tb[1]], b_to_a[tb[2]]};
    if (mapped == a.triangles[i]) {
      t_kept[i] = true;
      ++tj;
    }
  }
  std::size_t kept_triangles = tj;
  // A kept triangle must not use a removed vertex (it cannot, by construction) and a removed
  // vertex must not be used by a kept triangle: check, else rebuild.
  for (std::size_t i = 0; i < a.triangles.size(); ++i)
    if (t_kept[i])
      for (Index v : a.triangles[i])
        if (!a_kept[v]) return clear_and_add(a, b);
  std::size_t changes = (a.triangles.size() - kept_triangles) + (b.triangles.size() - kept_triangles) +
                        (a.positions.size() - kept_vertices) + (b.positions.size() - kept_vertices);
  if (changes > a.triangles.size() + b.triangles.size() + b.positions.size())
    return clear_and_add(a, b);
  for (std::size_t i = 0; i < a.triangles.size(); ++i)
    if (!t_kept[i]) edits.push_back(RemoveTriangle{static_cast<Index>(i)});
  for (std::size_t i = 0; i < a.positions.size(); ++i)
    if (!a_kept[i]) edits.push_back(RemoveVertex{static_cast<Index>(i)});
  for (std::size_t k = kept_vertices; k < b.positions.size(); ++k) edits.push_back(AddVertex{b.positions[k]});
  for (std::size_t k = kept_triangles; k < b.triangles.size(); ++k) {
    const auto& t = b.triangles[k];
    edits.push_back(AddTriangle{b_to_a[t[0]], b_to_a[t[1]], b_to_a[t[2]]});
  }
  // Exact by construction; verify cheaply on size, fall back when anything is off.
  try {
    if (apply_edits(a, edits) == b) return edits;
  } catch (const std::exception&) {
  }
  return clear_and_add(a, b);
}

}  // namespace meshflow::protocol
