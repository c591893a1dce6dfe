#pragma once
// A parsed workflow (thesis §5.1): an optional input URL and a body of tasks (atomic
// operations, if/else blocks, while loops). Every node keeps where it was in the document so
// validation errors can name the line and column.

#include <optional>
#include <string>
#include <vector>

namespace meshflow::engine {

struct Location {
  int line = 0;
  int column = 0;
};

struct Parameter {
  std::optional<std::string> name;  // named parameters; positional ones have none
  std::string value;
  Location at;
};

struct Condition {
  std::string analysis;              // an analysis operation's name
  std::string op = "EQ";             // EQ NEQ GT LT GEQ LEQ
  std::optional<std::string> value;  // default: 0 (natural, real) or true (boolean)
  Location at;
};

struct Task;
using Body = std::vector<Task>;

struct Task {
  enum class Kind { Atomic, If, While } kind = Kind::Atomic;
  Location at;
  // Atomic
  std::string name;
  std::vector<Parameter> parameters;
  // If and While
  Condition condition;
  Body body;
  Body else_body;  // If only
};

struct Workflow {
  std::optional<std::string> input_url;
  Body body;
};

// The names of the operations a workflow uses (atomic and analysis), each once, in order of
// first appearance.
std::vector<std::string> operations_used(const Workflow& workflow);

}  // namespace meshflow::engine
