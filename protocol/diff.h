#pragma once
// A correction for any operation that does not stream its edits (DESIGN §6): the edits that
// turn mesh `a` into mesh `b` exactly (apply_edits(a, diff) has b's canonical bytes).
// Small when b keeps a's vertices in order (moved or not) and some of its triangles in order,
// with new ones appended; otherwise it falls back to clearing a and adding b.

#include "mesh/mesh.h"
#include "protocol/edits.h"

namespace meshflow::protocol {

EditList diff_meshes(const mesh::Mesh& a, const mesh::Mesh& b);

}  // namespace meshflow::protocol
