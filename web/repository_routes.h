#pragma once
// The repository's routes on the hub (DESIGN §3, §7): semantic search and workflow CRUD,
// the purpose taxonomy and data types, the ontology document and the SPARQL endpoint.

#include "repository/repository.h"
#include "web/account_routes.h"
#include "web/hub_server.h"

namespace meshflow::web {

struct SparqlLimits {
  std::uint64_t max_rows = 10000;
  std::chrono::milliseconds timeout{5000};
  std::size_t max_body = 1 << 20;  // query text and workflow JSON
};

void add_repository_routes(HubServer& hub, repository::Repository& repo, Auth& auth,
                           SparqlLimits limits = {});

}  // namespace meshflow::web
