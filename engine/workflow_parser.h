#pragma once
// Reads workflow XML with Xerces-C, validated against engine/workflow.xsd (compiled into the
// binary). Safe for untrusted documents: no external entity, DTD or schema is ever loaded, and
// entity expansion is bounded (an XXE or billion-laughs document is refused).

#include <string>

#include "engine/workflow.h"

namespace meshflow::engine {

// \throws ParseError with the file name, line, column and the parser's reason.
Workflow parse_workflow(const std::string& xml, const std::string& name);
Workflow parse_workflow_file(const std::string& path);

// The XSD text (for `/api` documentation and tests).
const char* workflow_xsd();

}  // namespace meshflow::engine
