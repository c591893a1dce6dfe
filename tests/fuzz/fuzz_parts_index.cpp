// libFuzzer target: the parts-folder index decoder (partition.txt, mesh/part_files.h) on
// arbitrary bytes. It may refuse any input (ParseError) but must never crash; what it accepts
// must encode and decode back to the same index.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "mesh/errors.h"
#include "mesh/part_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  try {
    mesh::PartsIndex index = mesh::decode_parts_index({reinterpret_cast<const char*>(data), size}, "partition.txt");
    mesh::PartsIndex again = mesh::decode_parts_index(mesh::encode_parts_index(index), "again");
    if (again.parts != index.parts || again.diagonal != index.diagonal || again.adjacency != index.adjacency) std::abort();
  } catch (const InvalidInput&) {
  }
  return 0;
}
