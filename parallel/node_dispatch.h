#pragma once
// The per-part step on mesh nodes (DESIGN §4 POST /parts/simplify): the coordinator serves its
// parts directory's part files over HTTP itself (GET /parts/part-<p>.mfp, nothing else), each
// node fetches its part, simplifies it and answers the URL of the simplified part on its
// /files, which the coordinator downloads into the parts directory. One part per node at a
// time; a long run answers 202 and is polled at its task URL. A node that stops answering is
// dropped and its part goes to another node.
// Nodes started with --hub take part files only from the hub's host (the engine's split steps
// run inside the hub), the hub and registered nodes; pass their token.

#include <memory>
#include <string>
#include <vector>

#include "services/part_simplify.h"

namespace meshflow::parallel {

class NodeDispatch {
 public:
  // Starts serving `parts_dir` (on loopback when every node is on loopback, else on every
  // interface, advertised by this host's name) and checks each node answers /service.json.
  // \throws InvalidInput naming an unreachable or malformed node URL.
  // `token`: the node token, for nodes registered with a hub (their mutating routes need it).
  NodeDispatch(std::vector<std::string> node_urls, std::string parts_dir, std::string token = {});
  ~NodeDispatch();
  // Part p on a free node; blocks until done. \throws on a node's error, with its answer.
  services::PartStats run(std::size_t p, double max_error_abs);
  std::size_t nodes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::parallel
