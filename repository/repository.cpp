#include "repository/repository.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>
#include <functional>
#include <random>
#include <set>
#include <sstream>
#include <unordered_set>

#include "engine/validate.h"
#include "engine/workflow_parser.h"
#include "mesh/errors.h"
#include "repository/embedded.h"
#include "repository/search_index.h"
#include "services/operation.h"

namespace meshflow::repository {
namespace {

const std::string kRdfType = "http://www.w3.org/1999/02/22-rdf-syntax-ns#type";
const std::string kXsdDateTime = "http://www.w3.org/2001/XMLSchema#dateTime";
const std::string kPrefixes =
    "PREFIX wo: <http://meshflow.org/ontology/wo#>\n"
    "PREFIX rdfs: <http://www.w3.org/2000/01/rdf-schema#>\n";

std::string wo(const std::string& local) { return std::string(kWo) + local; }
std::string local_name(const std::string& uri) {
  auto cut = uri.find_last_of("#/");
  return cut == std::string::npos ? uri : uri.substr(cut + 1);
}
bool is_identifier(const std::string& s) {
  return !s.empty() && s.size() <= 128 &&
         std::all_of(s.begin(), s.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '_' || c == '-' || c == '.';
         });
}
std::string now_utc() {
  auto t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}
std::string fresh_id() {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream s;
  s << std::hex << rng();
  return s.str();
}
// The words of a free-text query, lowercased, with nothing that could leave a SPARQL string.
std::vector<std::string> words(const std::string& q) {
  std::vector<std::string> out;
  std::string cur;
  for (unsigned char c : q) {
    if (std::isalnum(c) || c >= 0x80 || c == '-' || c == '_') {
      cur += static_cast<char>(std::tolower(c));
    } else if (!cur.empty()) {
      out.push_back(cur);
      cur.clear();
    }
  }
  if (!cur.empty()) out.push_back(cur);
  if (out.size() > 8) out.resize(8);
  return out;
}

// The operation of the step a validation error points at: the step (or its parameter or
// condition) starting last at or before the error's line.
std::string operation_at(const engine::Workflow& workflow, std::uint64_t line) {
  std::string best;
  int best_line = 0;
  auto consider = [&](const engine::Location& at, const std::string& operation) {
    if (at.line > 0 && static_cast<std::uint64_t>(at.line) <= line && at.line >= best_line &&
        !operation.empty()) {
      best_line = at.line;
      best = operation;
    }
  };
  std::function<void(const engine::Body&)> walk = [&](const engine::Body& body) {
    for (const auto& task : body) {
      if (task.kind == engine::Task::Kind::Atomic) {
        consider(task.at, task.name);
        for (const auto& p : task.parameters) consider(p.at, task.name);
      } else {
        consider(task.at, task.condition.analysis);
        consider(task.condition.at, task.condition.analysis);
        walk(task.body);
        walk(task.else_body);
      }
    }
  };
  walk(workflow.body);
  return best;
}

struct Example {
  const char* id;
  const char* file;
  const char* xml;
  const char* name;
  const char* description;
  std::vector<std::string> domains;
};

std::vector<Example> examples() {
  return {
      {"mesh-repairing", "mesh_repairing.xml", embedded::kMeshRepairing, "Mesh Repairing",
       "The thesis's repair pipeline: keeps the largest connected component, smooths with two "
       "Laplacian steps, fills every hole and removes the degenerate triangles left behind.",
       {"HoleFilling", "Smoothing"}},
      {"conditional-repair", "conditional_repair.xml", embedded::kConditionalRepair,
       "Conditional mesh repair",
       "Repairs only what is wrong: removes small components when there is more than one, "
       "fills holes when boundary loops remain, otherwise removes degenerate triangles.",
       {"Cleaning", "HoleFilling"}},
      {"smoothing-loop", "smoothing_loop.xml", embedded::kSmoothingLoop, "Smoothing loop",
       "Applies one Laplacian smoothing step at a time while the average normal instability "
       "stays above 10 degrees (bounded by the hub's loop limit).",
       {"Smoothing"}},
      {"simplification", "simplification.xml", embedded::kSimplification,
       "Mesh simplification",
       "Quadric edge-collapse simplification within a maximum error of 0.5% of the diagonal; "
       "large meshes are split into parts and simplified on several nodes (thesis ch. 9).",
       {"Simplification"}},
  };
}

}  // namespace

struct Repository::Impl {
  std::filesystem::path dir;
  std::unique_ptr<RdfStore> store;
  std::unique_ptr<SearchIndex> index;
  std::map<std::string, std::string> purpose_parent;  // local name -> parent ("" = root)
  std::map<std::string, std::string> purpose_label;
  std::vector<std::string> datatypes;
  std::map<std::string, std::vector<std::string>> takes, gives;  // operation -> types
  std::size_t examples_loaded = 0;

  std::filesystem::path xml_path(const std::string& id) const {
    return dir / "workflows" / (id + ".xml");
  }

  void load_ontology_maps() {
    auto sub = store->query(kPrefixes +
                            "SELECT ?c ?p ?l WHERE { ?c rdfs:subClassOf ?p . ?c rdfs:label ?l }");
    std::map<std::string, std::string> parent;
    for (auto& row : sub.rows) {
      auto c = local_name(row[0].value);
      parent[c] = local_name(row[1].value);
      purpose_label[c] = row[2].value;
    }
    auto under = [&](std::string c, const std::string& root) {
      for (int guard = 0; guard < 64 && parent.count(c); ++guard) {
        c = parent[c];
        if (c == root) return true;
      }
      return false;
    };
    for (auto& [c, p] : parent) {
      if (under(c, "Purpose")) purpose_parent[c] = p == "Purpose" ? "" : p;
      if (under(c, "DataType")) datatypes.push_back(c);
    }
    for (const char* prop : {"takes", "gives"}) {
      auto r = store->query(kPrefixes + "SELECT ?o ?t WHERE { ?o wo:" + prop + " ?t }");
      auto& map = std::string(prop) == "takes" ? takes : gives;
      for (auto& row : r.rows) map[local_name(row[0].value)].push_back(local_name(row[1].value));
    }
  }

  // The purpose and every super-purpose (the closure written at insert, DESIGN §7).
  std::vector<std::string> closure(const std::vector<std::string>& domains) const {
    std::set<std::string> all;
    for (auto d : domains) {
      for (int guard = 0; guard < 64 && !d.empty(); ++guard) {
        all.insert(d);
        auto it = purpose_parent.find(d);
        d = it == purpose_parent.end() ? "" : it->second;
      }
    }
    return {all.begin(), all.end()};
  }
  // The most specific purposes of a closure (those no other member lies under).
  std::vector<std::string> most_specific(const std::vector<std::string>& all) const {
    std::set<std::string> ancestors;
    for (const auto& d : all) {
      auto it = purpose_parent.find(d);
      for (int guard = 0; guard < 64 && it != purpose_parent.end() && !it->second.empty();
           ++guard) {
        ancestors.insert(it->second);
        it = purpose_parent.find(it->second);
      }
    }
    std::vector<std::string> out;
    for (const auto& d : all)
      if (!ancestors.count(d)) out.push_back(d);
    return out;
  }

  std::string store_workflow(const NewWorkflow& w) {
    if (w.name.empty() || w.name.size() > 200)
      throw InvalidInput("a workflow needs a name of 1 to 200 characters");
    if (w.description.size() > 10000)
      throw InvalidInput("the description is longer than 10000 characters");
    if (w.type != "executable" && w.type != "static")
      throw InvalidInput("type must be \"executable\" or \"static\", not \"" + w.type + "\"");
    if (w.domains.empty()) throw InvalidInput("a workflow needs at least one purpose (domains)");
    for (const auto& d : w.domains)
      if (!purpose_parent.count(d)) throw InvalidInput("unknown purpose \"" + d + "\"");
    if (!is_identifier(w.creator)) throw InvalidInput("a workflow needs a creator");
    std::vector<std::string> ops = w.operations;
    if (w.type == "executable" || !w.xml.empty()) {
      if (w.xml.empty()) throw InvalidInput("an executable workflow needs its xml");
      auto parsed = engine::parse_workflow(w.xml, "workflow.xml");
      try {
        engine::validate_workflow(parsed, "workflow.xml", services::operation_specs());
      } catch (const ParseError& e) {
        auto op = e.where().line ? operation_at(parsed, *e.where().line) : std::string();
        if (op.empty()) throw;
        throw StepError(e, op);
      }
      ops = engine::operations_used(parsed);
    }
    for (const auto& op : ops)
      if (!is_identifier(op)) throw InvalidInput("bad operation name \"" + op + "\"");
    std::string id = w.id.empty() ? fresh_id() : w.id;
    std::string s = std::string(kWorkflowBase) + id;
    std::vector<Triple> t;
    auto lit = [&](const std::string& p, const std::string& v, const std::string& dt = "") {
      t.push_back({s, wo(p), v, true, dt});
    };
    auto res = [&](const std::string& p, const std::string& o) { t.push_back({s, p, o, false, ""}); };
    res(kRdfType, wo("Workflow"));
    res(kRdfType, wo(w.type == "static" ? "WorkflowStatic" : "WorkflowExecutable"));
    lit("name", w.name);
    lit("description", w.description);
    const std::string created = now_utc();
    lit("created", created, kXsdDateTime);
    res(wo("creator"), std::string(kUserBase) + w.creator);
    for (const auto& d : closure(w.domains)) res(wo("workflowDomain"), wo(d));
    std::set<std::string> seen;
    for (const auto& op : ops)
      if (seen.insert(op).second) res(wo("usesOperation"), wo(op));
    // Data: what the first operation takes, what the last gives.
    if (!ops.empty()) {
      for (const auto& ty : takes[ops.front()]) res(wo("inputType"), wo(ty));
      for (const auto& ty : gives[ops.back()]) res(wo("outputType"), wo(ty));
    }
    if (!w.xml.empty()) {
      std::filesystem::create_directories(dir / "workflows");
      auto path = xml_path(id);
      std::ofstream out(path, std::ios::binary);
      out << w.xml;
      if (!out.flush()) throw IoError("cannot write " + path.string());
      lit("xmlFile", "workflows/" + id + ".xml");
    }
    store->add(t);
    index->put({id, w.name, w.description, w.creator, created,
                most_specific(closure(w.domains)), w.type});
    return id;
  }

};

Repository::Repository(const std::filesystem::path& data_dir, const StoreConfig& config)
    : impl_(std::make_unique<Impl>()) {
  impl_->dir = data_dir / "repository";
  std::error_code ec;
  std::filesystem::create_directories(impl_->dir, ec);
  if (ec) throw IoError("cannot create " + impl_->dir.string() + ": " + ec.message());
  impl_->store = open_store(config, impl_->dir);
  bool first = impl_->store->created_now();
  impl_->index = std::make_unique<SearchIndex>(impl_->dir / "search.sqlite");
  if (first) impl_->index->clear();
  if (first) impl_->store->load_rdfxml(embedded::kOntology, "http://meshflow.org/ontology/wo");
  impl_->load_ontology_maps();
  if (first) {
    for (const auto& e : examples()) {
      NewWorkflow w{e.name, e.description, "meshflow", e.domains, "executable", e.xml, {}, e.id};
      impl_->store_workflow(w);
      ++impl_->examples_loaded;
    }
  } else {
    impl_->examples_loaded = examples().size();
    if (impl_->index->empty()) {  // a store from before the index: rebuild it from the triples
      auto r = impl_->store->query(kPrefixes + "SELECT ?w WHERE { ?w a wo:Workflow }");
      for (auto& row : r.rows)
        if (auto d = get(local_name(row[0].value))) impl_->index->put(*d);
    }
  }
}

Repository::~Repository() = default;

const char* ontology_rdfxml() { return embedded::kOntology; }

RdfStore& Repository::store() { return *impl_->store; }
std::size_t Repository::example_count() const { return impl_->examples_loaded; }

std::string Repository::create(const NewWorkflow& workflow) {
  NewWorkflow w = workflow;
  w.id.clear();
  return impl_->store_workflow(w);
}

std::optional<WorkflowDetail> Repository::get(const std::string& id) {
  if (!is_identifier(id)) return std::nullopt;
  auto r = impl_->store->query(kPrefixes + "SELECT ?p ?o WHERE { <" + kWorkflowBase + id +
                               "> ?p ?o }");
  if (r.rows.empty()) return std::nullopt;
  WorkflowDetail d;
  d.id = id;
  d.type = "executable";
  std::vector<std::string> domains;
  for (auto& row : r.rows) {
    auto p = local_name(row[0].value);
    auto o = row[1].value;
    if (p == "name") d.name = o;
    else if (p == "description") d.description = o;
    else if (p == "created") d.created = o;
    else if (p == "creator") d.creator = local_name(o);
    else if (p == "workflowDomain") domains.push_back(local_name(o));
    else if (p == "usesOperation") d.operations.push_back(local_name(o));
    else if (p == "inputType") d.inputs.push_back(local_name(o));
    else if (p == "outputType") d.outputs.push_back(local_name(o));
    else if (p == "type" && local_name(o) == "WorkflowStatic") d.type = "static";
  }
  d.domains = impl_->most_specific(domains);
  return d;
}

std::optional<std::string> Repository::xml(const std::string& id) {
  if (!is_identifier(id)) return std::nullopt;
  std::ifstream in(impl_->xml_path(id), std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool Repository::remove(const std::string& id) {
  if (!get(id)) return false;
  impl_->store->remove_subject(std::string(kWorkflowBase) + id);
  impl_->index->remove(id);
  std::error_code ec;
  std::filesystem::remove(impl_->xml_path(id), ec);
  return true;
}

SearchPage Repository::search(const SearchQuery& q) {
  // Filters of meaning: one basic graph pattern over the triples, selecting ids only (the
  // purpose closure is stored, so no path or UNION). Text and order: the FTS5 side index.
  std::string cls;
  if (q.type == "static") cls = "WorkflowStatic";
  else if (q.type == "executable") cls = "WorkflowExecutable";
  else if (!q.type.empty())
    throw InvalidInput("type must be static or executable, not \"" + q.type + "\"");
  // Each filter is one triple pattern (?w predicate object); the answer is their intersection.
  std::vector<std::pair<std::string, std::string>> patterns;
  auto filter = [&](const std::string& value, const char* what, const std::string& predicate,
                    const std::string& object) {
    if (value.empty()) return;
    if (!is_identifier(value)) throw InvalidInput(std::string("bad ") + what + " \"" + value + "\"");
    patterns.emplace_back(predicate, object);
  };
  if (!q.domain.empty() && !impl_->purpose_parent.count(q.domain))
    throw InvalidInput("unknown purpose \"" + q.domain + "\"");
  filter(q.creator, "creator", wo("creator"), std::string(kUserBase) + q.creator);
  filter(q.operation, "operation", wo("usesOperation"), wo(q.operation));
  filter(q.domain, "domain", wo("workflowDomain"), wo(q.domain));
  filter(q.input, "input", wo("inputType"), wo(q.input));
  filter(q.output, "output", wo("outputType"), wo(q.output));
  filter(cls, "type", kRdfType, wo(cls));
  std::optional<std::unordered_set<std::string>> allowed;
  std::unordered_set<std::string> not_runnable;
  if (q.runnable_with) {
    if (q.type == "static") return {{}, 0, q.offset, std::min<std::uint64_t>(q.limit, 200)};
    if (cls.empty()) patterns.emplace_back(kRdfType, wo("WorkflowExecutable"));
    // The workflows using an operation no node offers (no NOT EXISTS on Redland: the complement).
    std::string offered;
    for (const auto& op : *q.runnable_with) {
      if (!is_identifier(op)) throw InvalidInput("bad operation name \"" + op + "\"");
      offered += std::string(offered.empty() ? "" : " && ") + "?o != wo:" + op;
    }
    auto r = impl_->store->query(kPrefixes + "SELECT DISTINCT ?w WHERE { ?w wo:usesOperation ?o" +
                                 (offered.empty() ? "" : " . FILTER(" + offered + ")") + " }");
    for (auto& row : r.rows) not_runnable.insert(local_name(row[0].value));
  }
  for (const auto& [predicate, object] : patterns) {
    std::unordered_set<std::string> found;
    for (auto& uri : impl_->store->subjects(predicate, object)) {
      auto id = local_name(uri);
      if (!allowed || allowed->count(id)) found.insert(std::move(id));
    }
    allowed = std::move(found);
    if (allowed->empty()) break;
  }
  auto terms = words(q.q);
  SearchPage page;
  page.offset = q.offset;
  page.limit = std::min<std::uint64_t>(q.limit, 200);
  if (!allowed && not_runnable.empty() && !terms.empty()) {  // text alone: the index pages
    for (auto& id : impl_->index->match_page(terms, q.offset, page.limit, page.total))
      if (auto w = impl_->index->summary(id)) page.workflows.push_back(*w);
    return page;
  }
  std::vector<std::string> ordered = terms.empty() ? impl_->index->newest_first()
                                                   : impl_->index->match(terms);
  std::vector<std::string> hits;
  for (auto& id : ordered)
    if ((!allowed || allowed->count(id)) && !not_runnable.count(id)) hits.push_back(std::move(id));
  page.total = hits.size();
  for (auto i = q.offset; i < hits.size() && i < q.offset + page.limit; ++i)
    if (auto w = impl_->index->summary(hits[i])) page.workflows.push_back(*w);
  return page;
}

std::vector<Purpose> Repository::purposes() const {
  std::vector<Purpose> out;
  for (const auto& [name, parent] : impl_->purpose_parent) {
    Purpose p{name, impl_->purpose_label.count(name) ? impl_->purpose_label.at(name) : name, {}};
    if (!parent.empty()) p.parent = parent;
    out.push_back(p);
  }
  return out;
}

std::vector<std::string> Repository::datatypes() const { return impl_->datatypes; }

}  // namespace meshflow::repository
