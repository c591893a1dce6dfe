#include "repository/rdf_store.h"

#include "repository/redland_store.h"
#include "repository/virtuoso_store.h"

namespace meshflow::repository {

std::unique_ptr<RdfStore> open_store(const StoreConfig& config, const std::filesystem::path& dir) {
  if (config.virtuoso.empty()) return std::make_unique<RedlandStore>(dir);
  return std::make_unique<VirtuosoStore>(config);
}

}  // namespace meshflow::repository
