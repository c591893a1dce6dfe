// libFuzzer target: the workflow XML parser (Xerces-C against engine/workflow.xsd) and the
// validation against the operations, on arbitrary bytes. Either may refuse any input
// (InvalidInput, ParseError) but must never crash, hang or read out of bounds.
#include <cstdint>
#include <string>

#include "engine/validate.h"
#include "engine/workflow_parser.h"
#include "mesh/errors.h"
#include "services/operation.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  std::string xml(reinterpret_cast<const char*>(data), size);
  try {
    engine::Workflow workflow = engine::parse_workflow(xml, "fuzz.xml");
    engine::validate_workflow(workflow, "fuzz.xml", services::operation_specs());
    engine::operations_used(workflow);
  } catch (const InvalidInput&) {
  }
  return 0;
}
