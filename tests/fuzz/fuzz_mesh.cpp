// libFuzzer target: read_mesh_from_memory on arbitrary bytes: format and compression detection,
// gzip and zstd decoding, then whichever reader the content selects, into a real Mesh; the
// measures must then run on whatever was accepted.
#include <cstdint>
#include <span>

#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  try {
    mesh::Mesh m = mesh::read_mesh_from_memory({data, size}, "fuzz.mesh");
    mesh::compute_measures(m);
  } catch (const InvalidInput&) {
  } catch (const IoError&) {
  }
  return 0;
}
