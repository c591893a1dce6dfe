// repository_load N [VIRTUOSO_ENDPOINT]: fills a fresh repository with N workflows (Redland +
// sqlite, or the Virtuoso endpoint given), then measures semantic search latency (p50/p95 over
// mixed filters) and SPARQL queries per second with 8 client threads sharing the store
// (Redland: all through its one worker thread; Virtuoso: 8 HTTP connections).
// The workflows, searches and queries are the same for both (fixed random seed).
// Prints "key value" lines for bench/repository_bench.sh.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "repository/repository.h"

using namespace meshflow::repository;
using Clock = std::chrono::steady_clock;

static double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

int main(int argc, char** argv) {
  int n = argc > 1 ? std::atoi(argv[1]) : 10000;
  StoreConfig config;
  if (argc > 2) {
    config.virtuoso = argv[2];
    config.graph = "http://meshflow.org/bench/" + std::to_string(getpid());
  }
  auto dir = std::filesystem::temp_directory_path() / ("mf-repo-bench-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::mt19937 rng(42);
  const std::vector<std::string> words = {"scan", "statue", "terrain", "printing", "cleanup",
                                          "smooth", "repair", "archive", "cultural", "heritage",
                                          "mechanical", "part", "fast", "careful", "large"};
  const std::vector<std::string> domains = {"HoleFilling", "Cleaning", "Smoothing", "Simplification",
                                            "Visualization", "Printing3D", "Terrain",
                                            "VirtualReality", "FiniteElementAnalysis"};
  const std::vector<std::string> ops = {"LaplacianSmoothing", "FillHoles", "RemoveDegenerateTriangles",
                                        "RemoveSmallestComponents", "Simplify"};
  double load_ms = 0, search_p50 = 0, search_p95 = 0, qps = 0;
  {
    Repository repo(dir, config);
    auto t0 = Clock::now();
    for (int i = 0; i < n; ++i) {
      auto pick = [&](const std::vector<std::string>& v) { return v[rng() % v.size()]; };
      NewWorkflow w;
      w.name = pick(words) + " " + pick(words) + " " + std::to_string(i);
      w.description = "A " + pick(words) + " pipeline for " + pick(words) + " " + pick(words) + " meshes";
      w.creator = "user" + std::to_string(i % 50);
      w.domains = {pick(domains)};
      w.xml = "<workflow><body><atomic><name>" + pick(ops) + "</name></atomic><atomic><name>" +
              pick(ops) + "</name></atomic></body></workflow>";
      repo.create(w);
    }
    load_ms = ms_since(t0);
    std::vector<SearchQuery> queries;
    for (int i = 0; i < 20; ++i) {
      SearchQuery a; a.q = words[i % words.size()]; queries.push_back(a);
      SearchQuery b; b.domain = i % 2 ? "Repair" : domains[i % domains.size()]; queries.push_back(b);
      SearchQuery c; c.operation = ops[i % ops.size()]; c.q = words[(i + 3) % words.size()]; queries.push_back(c);
      SearchQuery d; d.creator = "user" + std::to_string(i); queries.push_back(d);
      SearchQuery e; e.type = "executable"; e.offset = 100; queries.push_back(e);
    }
    std::vector<double> lat;
    const char* kinds[] = {"text", "purpose", "operation_text", "creator", "type_paged"};
    std::vector<double> worst(5, 0.0);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      auto t = Clock::now();
      repo.search(queries[i]);
      lat.push_back(ms_since(t));
      worst[i % 5] = std::max(worst[i % 5], lat.back());
    }
    for (int k = 0; k < 5; ++k) std::printf("search_max_ms_%s %.1f\n", kinds[k], worst[k]);
    std::sort(lat.begin(), lat.end());
    search_p50 = lat[lat.size() / 2];
    search_p95 = lat[lat.size() * 95 / 100];
    // SPARQL: 8 clients, mixed point lookups and filtered selects, for 10 s.
    const std::vector<std::string> sparql = {
        "SELECT ?p ?o WHERE { <http://meshflow.org/workflow/mesh-repairing> ?p ?o }",
        "PREFIX wo: <http://meshflow.org/ontology/wo#> SELECT ?w WHERE { ?w wo:usesOperation wo:FillHoles ; wo:workflowDomain wo:Terrain } LIMIT 20",
        "PREFIX wo: <http://meshflow.org/ontology/wo#> SELECT ?w ?n WHERE { ?w wo:creator <http://meshflow.org/user/user7> ; wo:name ?n }"};
    std::atomic<long> done{0};
    std::atomic<bool> stop{false};
  std::atomic<long> failed{0};
    std::vector<std::thread> clients;
    auto t1 = Clock::now();
    for (int c = 0; c < 8; ++c)
      clients.emplace_back([&, c] {
        for (int i = c; !stop; ++i) {
          try {
            QueryLimits slow;
            slow.timeout = std::chrono::milliseconds(120000);
            repo.store().query(sparql[i % sparql.size()], slow);
            ++done;
          } catch (const std::exception& e) {
            ++failed;
          }
        }
      });
    std::this_thread::sleep_for(std::chrono::seconds(10));
    stop = true;
    for (auto& t : clients) t.join();
    qps = done / (ms_since(t1) / 1000.0);
    if (failed) std::printf("sparql_failed %ld\n", failed.load());
  }
  std::filesystem::remove_all(dir);
  std::printf("workflows %d\nload_s %.1f\nsearch_p50_ms %.1f\nsearch_p95_ms %.1f\nsparql_qps_8 %.1f\n",
              n, load_ms / 1000, search_p50, search_p95, qps);
}
