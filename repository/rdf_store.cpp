#include "repository/rdf_store.h"

#include <cctype>

#include "repository/redland_store.h"
#include "repository/virtuoso_store.h"

namespace meshflow::repository {

std::string sparql_first_keyword(const std::string& text) {
  std::size_t i = 0, n = text.size();
  auto skip_space = [&] {
    while (i < n) {
      if (std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      else if (text[i] == '#') { while (i < n && text[i] != '\n') ++i; }
      else break;
    }
  };
  for (;;) {
    skip_space();
    std::size_t b = i;
    while (i < n && std::isalpha(static_cast<unsigned char>(text[i]))) ++i;
    std::string word = text.substr(b, i - b);
    for (auto& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (word != "prefix" && word != "base") return word;
    skip_space();
    if (word == "prefix") { while (i < n && text[i] != '<') ++i; }
    while (i < n && text[i] != '>') ++i;
    if (i < n) ++i;
  }
}

std::unique_ptr<RdfStore> open_store(const StoreConfig& config, const std::filesystem::path& dir) {
  if (config.virtuoso.empty()) return std::make_unique<RedlandStore>(dir);
  return std::make_unique<VirtuosoStore>(config);
}

}  // namespace meshflow::repository
