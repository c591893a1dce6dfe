// libFuzzer target: the Rem-file decoder (mesh/part_files.h) on arbitrary bytes. It may refuse
// any input (ParseError) but must never crash, read out of bounds or allocate absurdly; what it
// accepts must encode back to the same bytes.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "mesh/errors.h"
#include "mesh/part_files.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  try {
    mesh::RemFile rem = mesh::decode_rem({data, size}, "fuzz.rem");
    std::vector<std::uint8_t> again = mesh::encode_rem(rem);
    if (again.size() != size || !std::equal(again.begin(), again.end(), data)) std::abort();
  } catch (const InvalidInput&) {
  }
  return 0;
}
