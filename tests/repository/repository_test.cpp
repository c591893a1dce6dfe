// The repository in a temporary data folder, on the default backend (Redland + sqlite), or on
// Virtuoso when MESHFLOW_VIRTUOSO names its SPARQL endpoint (tests/repository/with_virtuoso.sh
// starts one): the same tests for both, each Virtuoso test in a graph of its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>

#include "mesh/errors.h"
#include "repository/repository.h"

namespace meshflow::repository {
namespace {

namespace fs = std::filesystem;

StoreConfig backend_under_test(const std::string& test_id) {
  StoreConfig config;
  if (const char* endpoint = std::getenv("MESHFLOW_VIRTUOSO"); endpoint && *endpoint) {
    config.virtuoso = endpoint;
    config.graph = "http://meshflow.org/test/" + test_id;
  }
  return config;
}

class RepositoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto id = std::to_string(std::random_device{}());
    dir = fs::temp_directory_path() / ("mf-repo-" + id);
    config = backend_under_test(id);
    repo = std::make_unique<Repository>(dir, config);
  }
  bool virtuoso() const { return !config.virtuoso.empty(); }
  void TearDown() override {
    repo.reset();
    fs::remove_all(dir);
  }
  bool finds(const SearchQuery& q, const std::string& id) {
    auto page = repo->search(q);
    return std::any_of(page.workflows.begin(), page.workflows.end(),
                       [&](const WorkflowSummary& w) { return w.id == id; });
  }
  fs::path dir;
  StoreConfig config;
  std::unique_ptr<Repository> repo;
};

TEST_F(RepositoryTest, RunsOnTheBackendAsked) {
  EXPECT_EQ(repo->store().backend(), virtuoso() ? "virtuoso" : "redland");
}

const char* kSmooth =
    "<workflow><body><atomic><name>LaplacianSmoothing</name></atomic></body></workflow>";

TEST_F(RepositoryTest, FirstStartLoadsTheExamples) {
  EXPECT_EQ(repo->example_count(), 4u);
  auto w = repo->get("mesh-repairing");
  ASSERT_TRUE(w);
  EXPECT_EQ(w->name, "Mesh Repairing");
  std::vector<std::string> domains = w->domains;
  std::sort(domains.begin(), domains.end());
  EXPECT_EQ(domains, (std::vector<std::string>{"HoleFilling", "Smoothing"}));
  EXPECT_EQ(w->operations.size(), 4u);
  EXPECT_EQ(w->inputs, std::vector<std::string>{"TriangleMesh"});
  EXPECT_EQ(w->creator, "meshflow");
  ASSERT_TRUE(repo->xml("mesh-repairing"));
}

TEST_F(RepositoryTest, APurposeFindsTheWorkflowsOfItsSubPurposes) {
  SearchQuery q;
  q.domain = "Repair";
  EXPECT_TRUE(finds(q, "mesh-repairing"));
  EXPECT_TRUE(finds(q, "smoothing-loop"));
  EXPECT_FALSE(finds(q, "simplification"));
  q.domain = "HoleFilling";
  EXPECT_FALSE(finds(q, "smoothing-loop"));
  q.domain = "NoSuchPurpose";
  EXPECT_THROW(repo->search(q), InvalidInput);
}

TEST_F(RepositoryTest, FreeTextNeedsEveryWord) {
  SearchQuery q;
  q.q = "repair";
  auto page = repo->search(q);
  ASSERT_EQ(page.total, 2u);  // the two with "repair" in name and description, not the others
  std::set<std::string> ids{page.workflows[0].id, page.workflows[1].id};
  EXPECT_EQ(ids, (std::set<std::string>{"mesh-repairing", "conditional-repair"}));
  q.q = "laplacian smooth";  // every word must appear, as a word prefix
  page = repo->search(q);
  EXPECT_TRUE(finds(q, "smoothing-loop"));
  EXPECT_TRUE(finds(q, "mesh-repairing"));
  EXPECT_FALSE(finds(q, "conditional-repair"));
  q.q = "\"; DROP } # nothing";
  EXPECT_EQ(repo->search(q).total, 0u);
}

TEST_F(RepositoryTest, FiltersByOperationTypeCreatorAndKind) {
  SearchQuery q;
  q.operation = "Simplify";
  auto page = repo->search(q);
  ASSERT_EQ(page.total, 1u);
  EXPECT_EQ(page.workflows[0].id, "simplification");
  q = {};
  q.input = "TriangleMesh";
  EXPECT_TRUE(finds(q, "mesh-repairing"));
  q = {};
  q.output = "HeightField";
  EXPECT_EQ(repo->search(q).total, 0u);
  q = {};
  q.type = "static";
  EXPECT_EQ(repo->search(q).total, 0u);
  q = {};
  q.creator = "meshflow";
  q.limit = 2;
  page = repo->search(q);
  EXPECT_EQ(page.total, 4u);
  EXPECT_EQ(page.workflows.size(), 2u);
}

TEST_F(RepositoryTest, CreateStoresAndDeleteRemovesEverything) {
  auto before = repo->store().size();
  NewWorkflow w{"My smoothing", "Two steps", "alice", {"Smoothing"}, "executable", kSmooth, {}, ""};
  auto id = repo->create(w);
  ASSERT_TRUE(repo->get(id));
  EXPECT_EQ(repo->get(id)->creator, "alice");
  EXPECT_FALSE(repo->get(id)->created.empty());
  SearchQuery q;
  q.creator = "alice";
  EXPECT_TRUE(finds(q, id));
  EXPECT_TRUE(repo->remove(id));
  EXPECT_FALSE(finds(q, id));  // no answer remembered from before the delete
  NewWorkflow again = w;
  auto id2 = repo->create(again);
  EXPECT_TRUE(finds(q, id2));  // nor from before a create
  EXPECT_TRUE(repo->remove(id2));
  EXPECT_FALSE(repo->get(id));
  EXPECT_FALSE(repo->xml(id));
  EXPECT_EQ(repo->store().size(), before);
  EXPECT_TRUE(repo->get("mesh-repairing"));
  EXPECT_FALSE(repo->remove(id));
}

TEST_F(RepositoryTest, StaticWorkflowsNeedNoXml) {
  NewWorkflow w{"Printing prep", "Docs", "curator", {"Printing3D"}, "static", "",
                {"FillHoles", "Simplify"}, ""};
  auto id = repo->create(w);
  auto got = repo->get(id);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->type, "static");
  EXPECT_EQ(got->operations.size(), 2u);
}

TEST_F(RepositoryTest, BadWorkflowsAreRefusedWithWhere) {
  NewWorkflow w{"Bad", "", "alice", {"Smoothing"}, "executable", "<workflow><body>", {}, ""};
  try {
    repo->create(w);
    FAIL() << "malformed XML accepted";
  } catch (const ParseError& e) {
    EXPECT_TRUE(e.where().line.has_value());
  }
  w.xml = "<workflow><body>\n<atomic><name>Frobnicate</name></atomic></body></workflow>";
  try {
    repo->create(w);
    FAIL() << "unknown operation accepted";
  } catch (const StepError& e) {
    EXPECT_EQ(e.where().line.value_or(0), 2u);
    EXPECT_EQ(e.operation(), "Frobnicate");
    EXPECT_NE(std::string(e.what()).find("Frobnicate"), std::string::npos);
  }
  w.xml = "<workflow><body>\n<atomic><name>FillHoles</name></atomic>\n"
          "<atomic><name>LaplacianSmoothing</name>"
          "<parameters><parameter name=\"iterations\">-4</parameter></parameters>"
          "</atomic></body></workflow>";
  try {
    repo->create(w);
    FAIL() << "a negative step count accepted";
  } catch (const StepError& e) {
    EXPECT_EQ(e.where().line.value_or(0), 3u);
    EXPECT_EQ(e.operation(), "LaplacianSmoothing");
  }
  w.xml = kSmooth;
  w.domains = {"Juggling"};
  EXPECT_THROW(repo->create(w), InvalidInput);
  w.domains = {};
  EXPECT_THROW(repo->create(w), InvalidInput);
}

TEST_F(RepositoryTest, SparqlErrorsAndBounds) {
  EXPECT_THROW(repo->store().query("SELEC ?x WHERE"), ParseError);
  const std::string path = "PREFIX rdfs: <http://www.w3.org/2000/01/rdf-schema#> "
                           "SELECT ?p WHERE { <http://meshflow.org/ontology/wo#HoleFilling> "
                           "rdfs:subClassOf+ ?p }";
  if (virtuoso()) {  // full SPARQL 1.1: the purpose's ancestors by a property path
    auto r = repo->store().query(path);
    std::set<std::string> up;
    for (auto& row : r.rows) up.insert(row[0].value);
    EXPECT_TRUE(up.count("http://meshflow.org/ontology/wo#Repair"));
    EXPECT_TRUE(up.count("http://meshflow.org/ontology/wo#Purpose"));
  } else  // rasqal 0.9.33 has no property paths: a clear refusal
    EXPECT_THROW(repo->store().query(path), ParseError);
  QueryLimits few;
  few.max_rows = 5;
  EXPECT_THROW(repo->store().query("SELECT ?s ?p ?o WHERE { ?s ?p ?o }", few), LimitExceeded);
  auto r = repo->store().query("SELECT ?s WHERE { ?s ?p ?o } LIMIT 5", few);
  EXPECT_EQ(r.rows.size(), 5u);
  auto ask = repo->store().query(
      "ASK { <http://meshflow.org/workflow/mesh-repairing> ?p ?o }");
  EXPECT_EQ(ask.kind, QueryResult::Kind::Boolean);
  EXPECT_TRUE(ask.boolean);
}

TEST_F(RepositoryTest, AQueryPastItsTimeBoundIsStopped) {
  // A four-way cross product of every triple: billions of rows, never finished in 300 ms.
  QueryLimits quick;
  quick.timeout = std::chrono::milliseconds(300);
  quick.max_rows = 1ull << 40;
  auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(repo->store().query("SELECT * WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i . ?j ?k ?l }",
                                   quick),
               QueryTimeout);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

TEST_F(RepositoryTest, ARunawayQueryDoesNotHoldUpTheNext) {
  // Sorting a three-way cross product: the whole of it is computed before the first row.
  QueryLimits quick;
  quick.timeout = std::chrono::milliseconds(300);
  quick.max_rows = 1ull << 40;
  EXPECT_THROW(repo->store().query("SELECT ?a WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i } "
                                   "ORDER BY ?c ?f ?i",
                                   quick),
               QueryTimeout);
  auto start = std::chrono::steady_clock::now();
  auto ask = repo->store().query("ASK { <http://meshflow.org/workflow/mesh-repairing> ?p ?o }");
  EXPECT_TRUE(ask.boolean);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(1));
}

TEST_F(RepositoryTest, RunnableNeedsEveryOperationOffered) {
  SearchQuery q;
  q.runnable_with = std::vector<std::string>{"LaplacianSmoothing", "AverageNormalInstability"};
  auto page = repo->search(q);
  std::set<std::string> ids;
  for (auto& w : page.workflows) ids.insert(w.id);
  EXPECT_EQ(ids, std::set<std::string>{"smoothing-loop"});
  q.runnable_with = std::vector<std::string>{};
  EXPECT_EQ(repo->search(q).total, 0u);
  NewWorkflow doc{"Printing prep", "Docs", "curator", {"Printing3D"}, "static", "",
                  {"Simplify"}, ""};
  repo->create(doc);
  q.runnable_with = std::vector<std::string>{"Simplify"};
  page = repo->search(q);
  ASSERT_EQ(page.total, 1u);  // the executable one, not the documentation
  EXPECT_EQ(page.workflows[0].id, "simplification");
}

TEST_F(RepositoryTest, ReopeningKeepsTheStoreAndDoesNotReload) {
  NewWorkflow w{"Kept", "", "bob", {"Terrain"}, "executable", kSmooth, {}, ""};
  auto id = repo->create(w);
  auto size = repo->store().size();
  repo.reset();
  repo = std::make_unique<Repository>(dir, config);
  EXPECT_EQ(repo->store().size(), size);
  EXPECT_TRUE(repo->get(id));
}

}  // namespace
}  // namespace meshflow::repository
