// libFuzzer target: the part-file decoder (mesh/part_files.h) on arbitrary bytes. It may refuse
// any input (ParseError) but must never crash, read out of bounds or allocate absurdly; what it
// accepts must encode back to the same bytes.
#include <cstdint>
#include <algorithm>
#include <cstdlib>
#include <span>

#include "mesh/errors.h"
#include "mesh/part_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  try {
    mesh::PartFile part = mesh::decode_part({data, size}, "fuzz.part");
    std::vector<std::uint8_t> again = mesh::encode_part(part);
    if (again.size() != size || !std::equal(again.begin(), again.end(), data)) std::abort();
  } catch (const InvalidInput&) {
  }
  return 0;
}
