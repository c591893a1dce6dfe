#pragma once
// The per-part step on mesh nodes (DESIGN §4 POST /parts/simplify): the coordinator serves its
// parts directory over HTTP itself, each node fetches its part, simplifies it and answers the
// URL of the simplified part on its /files, which the coordinator downloads into the parts
// directory. The Rem scheme (parallel/distributed_simplify.h) goes over the wire: the request
// names the Rem files of p's simplified neighbours ("removed": [{"from_part", "url"}]) and,
// for each neighbour still to come, its side of their seam as partitioned ("unprocessed":
// [{"part", "url"}], for the checks there); the node answers a Rem file per unprocessed
// neighbour ("removed": [{"to_part", "url", "sha256"}]), fetched into DIR/rem-<p>-<r>.bin
// before the part. Served: GET /parts/part-<p>.mfp, /parts/rem-<q>-<p>.bin and
// /parts/seam-<r>-<p>.mfp, nothing else. One part per node at a time; a
// long run answers 202 and is polled at its task URL. A node that stops answering is dropped
// and its part goes to another node.
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
  services::PartStats run(std::size_t p, double max_error_abs, bool fixed_seams = false);
  std::size_t nodes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::parallel
