#include "repository/virtuoso_store.h"

#include <curl/curl.h>
#include <raptor2.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>

#include "mesh/errors.h"

namespace meshflow::repository {
namespace {

using nlohmann::json;

constexpr std::size_t kMaxResponseBytes = std::size_t{1} << 30;
constexpr std::size_t kTriplesPerUpdate = 2000;

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string first_line(const std::string& text) {
  auto s = text.substr(0, text.find('\n'));
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s.size() > 400 ? s.substr(0, 400) + "..." : s;
}

// <iri> for SPARQL; refuses what cannot be written inside <>.
std::string iri(const std::string& value) {
  for (unsigned char c : value)
    if (c <= 0x20 || c == '<' || c == '>' || c == '"' || c == '{' || c == '}' || c == '|' ||
        c == '^' || c == '`' || c == '\\')
      throw InvalidInput("not an IRI that SPARQL can carry: \"" + value + "\"");
  return "<" + value + ">";
}

// "text" for SPARQL, with escapes for quote, backslash and control characters.
std::string quoted(const std::string& value) {
  std::string out = "\"";
  for (unsigned char c : value) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04X", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string triple_text(const Triple& t) {
  std::string object = t.literal ? quoted(t.object) + (t.datatype.empty() ? "" : "^^" + iri(t.datatype))
                                 : iri(t.object);
  return iri(t.subject) + " " + iri(t.predicate) + " " + object + " .\n";
}

size_t collect(char* data, size_t size, size_t count, void* user) {
  auto* out = static_cast<std::string*>(user);
  if (out->size() + size * count > kMaxResponseBytes) return 0;  // aborts the transfer
  out->append(data, size * count);
  return size * count;
}

size_t collect_header(char* data, size_t size, size_t count, void* user) {
  auto* headers = static_cast<std::string*>(user);
  headers->append(data, size * count);
  return size * count;
}

struct Response {
  long status = 0;
  std::string body, headers;
};

// The RDF/XML document as SPARQL triple lines (raptor writes each term in N-Triples form).
struct RdfXmlLines {
  std::vector<std::string> lines;
  std::string error;
  int error_line = 0;
};

void on_statement(void* user, raptor_statement* s) {
  auto* out = static_cast<RdfXmlLines*>(user);
  std::string line;
  for (raptor_term* term : {s->subject, s->predicate, s->object}) {
    unsigned char* text = raptor_term_to_string(term);
    if (!text) return;
    line += reinterpret_cast<const char*>(text);
    line += ' ';
    raptor_free_memory(text);
  }
  out->lines.push_back(line + ".\n");
}

void on_log(void* user, raptor_log_message* message) {
  auto* out = static_cast<RdfXmlLines*>(user);
  if (message->level < RAPTOR_LOG_LEVEL_ERROR || !out->error.empty()) return;
  out->error = message->text ? message->text : "error";
  if (message->locator) out->error_line = raptor_locator_line(message->locator);
}

}  // namespace

std::string query_form(const std::string& text) {
  std::string word = sparql_first_keyword(text);
  for (const char* form : {"select", "ask", "construct", "describe"})
    if (word == form) return word;
  return "";
}

QueryResult parse_sparql_json(const std::string& body, std::uint64_t max_rows) {
  auto bad = [](const std::string& what) {
    return ParseError({"SPARQL JSON results", std::nullopt, std::nullopt, std::nullopt}, what);
  };
  json j;
  try {
    j = json::parse(body);
  } catch (const json::parse_error& e) {
    throw ParseError({"SPARQL JSON results", std::nullopt, std::nullopt, e.byte},
                     std::string("not JSON: ") + e.what());
  } catch (const json::exception& e) {  // e.g. a number out of range (found by fuzz_sparql_results)
    throw ParseError({"SPARQL JSON results", std::nullopt, std::nullopt, std::nullopt},
                     std::string("not JSON we can read: ") + e.what());
  }
  if (!j.is_object()) throw bad("the results are not a JSON object");
  QueryResult out;
  if (j.contains("boolean")) {
    if (!j["boolean"].is_boolean()) throw bad("\"boolean\" is not true or false");
    out.kind = QueryResult::Kind::Boolean;
    out.boolean = j["boolean"].get<bool>();
    return out;
  }
  auto head = j.find("head");
  if (head == j.end() || !head->is_object()) throw bad("no \"head\" object");
  auto vars = head->find("vars");
  if (vars == head->end() || !vars->is_array()) throw bad("no \"head\".\"vars\" list");
  for (const auto& v : *vars) {
    if (!v.is_string()) throw bad("a variable name in \"vars\" is not a string");
    out.variables.push_back(v.get<std::string>());
  }
  auto results = j.find("results");
  if (results == j.end() || !results->is_object()) throw bad("no \"results\" object");
  auto bindings = results->find("bindings");
  if (bindings == results->end() || !bindings->is_array())
    throw bad("no \"results\".\"bindings\" list");
  if (bindings->size() > max_rows)
    throw LimitExceeded("query result rows (add a LIMIT or narrow the query)", max_rows,
                        bindings->size());
  auto text = [&](const json& o, const char* key, bool required) -> std::string {
    auto it = o.find(key);
    if (it == o.end()) {
      if (required) throw bad(std::string("a term has no \"") + key + "\"");
      return {};
    }
    if (!it->is_string()) throw bad(std::string("a term's \"") + key + "\" is not a string");
    return it->get<std::string>();
  };
  out.rows.reserve(bindings->size());
  std::size_t index = 0;
  for (const auto& b : *bindings) {
    if (!b.is_object()) throw bad("binding " + std::to_string(index) + " is not an object");
    std::vector<Term> row(out.variables.size());
    for (std::size_t i = 0; i < out.variables.size(); ++i) {
      auto it = b.find(out.variables[i]);
      if (it == b.end()) continue;  // unbound
      if (!it->is_object()) throw bad("a term of binding " + std::to_string(index) + " is not an object");
      std::string type = text(*it, "type", true);
      Term& t = row[i];
      t.value = text(*it, "value", true);
      if (type == "uri") {
        t.kind = Term::Kind::Uri;
      } else if (type == "bnode") {
        t.kind = Term::Kind::Blank;
      } else if (type == "literal" || type == "typed-literal") {
        t.kind = Term::Kind::Literal;
        t.datatype = text(*it, "datatype", false);
        t.language = text(*it, "xml:lang", false);
      } else {
        throw bad("unknown term type \"" + type + "\" in binding " + std::to_string(index));
      }
    }
    out.rows.push_back(std::move(row));
    ++index;
  }
  return out;
}

StoreConfig StoreConfig::parse(const std::string& spec) {
  StoreConfig c;
  if (spec.empty() || spec == "redland") return c;
  const std::string prefix = "virtuoso=";
  if (spec.rfind(prefix, 0) != 0)
    throw InvalidInput("--store must be 'redland' or 'virtuoso=URL[,graph=URI][,user=U][,password=P]', not \"" +
                       spec + "\"");
  std::size_t at = prefix.size();
  bool first = true;
  while (at <= spec.size()) {
    auto comma = spec.find(',', at);
    std::string part = spec.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    if (first) {
      c.virtuoso = part;
      first = false;
    } else {
      auto eq = part.find('=');
      std::string key = part.substr(0, eq), value = eq == std::string::npos ? "" : part.substr(eq + 1);
      if (key == "graph") c.graph = value;
      else if (key == "user") c.user = value;
      else if (key == "password") c.password = value;
      else throw InvalidInput("--store: unknown option \"" + key + "\" (graph, user, password)");
    }
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  if (c.virtuoso.rfind("http://", 0) != 0 && c.virtuoso.rfind("https://", 0) != 0)
    throw InvalidInput("--store virtuoso=URL needs an http(s) URL of the SPARQL endpoint, not \"" +
                       c.virtuoso + "\"");
  if (c.graph.empty()) throw InvalidInput("--store: graph= needs a graph URI");
  return c;
}

struct VirtuosoStore::Impl {
  StoreConfig config;
  std::string update_url;
  bool created = false;
  std::mutex mutex;
  std::vector<CURL*> idle;  // kept for their open connections

  ~Impl() {
    for (CURL* c : idle) curl_easy_cleanup(c);
  }

  CURL* take() {
    {
      std::lock_guard lock(mutex);
      if (!idle.empty()) {
        CURL* c = idle.back();
        idle.pop_back();
        curl_easy_reset(c);
        return c;
      }
    }
    CURL* c = curl_easy_init();
    if (!c) throw IoError("libcurl cannot start a request");
    return c;
  }
  void give_back(CURL* c) {
    std::lock_guard lock(mutex);
    if (idle.size() < 16) idle.push_back(c);
    else curl_easy_cleanup(c);
  }

  // POSTs the form to `url`. \throws QueryTimeout (past `timeout`), IoError.
  Response post(const std::string& url, const std::vector<std::pair<std::string, std::string>>& form,
                const std::string& accept, std::chrono::milliseconds timeout, bool authenticate) {
    CURL* c = take();
    struct Return {
      Impl* self; CURL* c;
      ~Return() { self->give_back(c); }
    } give{this, c};
    std::string body;
    for (const auto& [k, v] : form) {
      char* e = curl_easy_escape(c, v.data(), static_cast<int>(v.size()));
      if (!e) throw IoError("libcurl cannot encode a form field");
      body += (body.empty() ? "" : "&") + k + "=" + e;
      curl_free(e);
    }
    Response r;
    curl_slist* headers = nullptr;
    headers = curl_slist_append(headers, ("Accept: " + accept).c_str());
    headers = curl_slist_append(headers, "Content-Type: application/x-www-form-urlencoded; charset=UTF-8");
    std::unique_ptr<curl_slist, void (*)(curl_slist*)> own(headers, curl_slist_free_all);
    curl_easy_setopt(c, CURLOPT_URL, url.c_str());
    curl_easy_setopt(c, CURLOPT_HTTPHEADER, headers);
    curl_easy_setopt(c, CURLOPT_POSTFIELDS, body.c_str());
    curl_easy_setopt(c, CURLOPT_POSTFIELDSIZE_LARGE, static_cast<curl_off_t>(body.size()));
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, collect);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &r.body);
    curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, collect_header);
    curl_easy_setopt(c, CURLOPT_HEADERDATA, &r.headers);
    curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS, 5000L);
    curl_easy_setopt(c, CURLOPT_TIMEOUT_MS, static_cast<long>(timeout.count()));
    curl_easy_setopt(c, CURLOPT_ACCEPT_ENCODING, "");
    if (authenticate) {
      curl_easy_setopt(c, CURLOPT_HTTPAUTH, CURLAUTH_DIGEST);
      curl_easy_setopt(c, CURLOPT_USERNAME, config.user.c_str());
      curl_easy_setopt(c, CURLOPT_PASSWORD, config.password.c_str());
    }
    CURLcode rc = curl_easy_perform(c);
    if (rc == CURLE_OPERATION_TIMEDOUT)
      throw QueryTimeout("Virtuoso did not answer within " + std::to_string(timeout.count()) + " ms");
    if (rc != CURLE_OK)
      throw IoError("cannot reach Virtuoso at " + url + ": " + curl_easy_strerror(rc));
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &r.status);
    return r;
  }

  // Turns a refusal by Virtuoso into our errors.
  [[noreturn]] void refused(const Response& r, const std::string& what,
                            std::chrono::milliseconds timeout) {
    std::string line = first_line(r.body);
    if (r.body.find("S1TAT") != std::string::npos || r.body.find("timeout") != std::string::npos)
      throw QueryTimeout("the query ran past its time bound of " + std::to_string(timeout.count()) +
                         " ms (Virtuoso: " + line + ")");
    if (r.status == 401 || r.status == 403)
      throw IoError("Virtuoso refused the " + what + " (HTTP " + std::to_string(r.status) +
                    "): check user and password of --store");
    if ((r.status >= 400 && r.status < 500) || r.body.find(" Error SP") != std::string::npos ||
        r.body.find("37000") != std::string::npos)
      throw ParseError({"query", std::nullopt, std::nullopt, std::nullopt},
                       "the Virtuoso backend cannot run this " + what + ": " + line);
    throw IoError("Virtuoso failed on the " + what + " (HTTP " + std::to_string(r.status) +
                  "): " + line);
  }

  void update(const std::string& text) {
    const std::chrono::milliseconds timeout{120000};
    auto r = post(update_url, {{"query", text}}, "application/sparql-results+json", timeout, true);
    if (r.status != 200) refused(r, "update", timeout);
  }

  void insert(const std::vector<std::string>& lines) {
    for (std::size_t at = 0; at < lines.size(); at += kTriplesPerUpdate) {
      std::string text = "INSERT DATA { GRAPH " + iri(config.graph) + " {\n";
      for (std::size_t i = at; i < lines.size() && i < at + kTriplesPerUpdate; ++i) text += lines[i];
      update(text + "} }");
    }
  }
};

VirtuosoStore::VirtuosoStore(const StoreConfig& config) : impl_(std::make_unique<Impl>()) {
  static std::once_flag curl_ready;
  std::call_once(curl_ready, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
  impl_->config = config;
  impl_->update_url = config.virtuoso + "-auth";
  iri(config.graph);
  impl_->created = size() == 0;
}

VirtuosoStore::~VirtuosoStore() = default;

bool VirtuosoStore::created_now() const { return impl_->created; }

QueryResult VirtuosoStore::query(const std::string& sparql, const QueryLimits& limits,
                                 const std::string& graph_format) {
  std::string form = query_form(sparql);
  bool graph = form == "construct" || form == "describe";
  std::string accept = !graph ? "application/sparql-results+json"
                       : graph_format == "rdfxml" ? "application/rdf+xml"
                                                  : "text/turtle";
  // Virtuoso's own bound (`timeout`, ms) answers partial results with X-SQL-State S1TAT; the
  // transfer's bound catches the rest. Either way the caller gets QueryTimeout, never a part.
  auto r = impl_->post(impl_->config.virtuoso,
                       {{"query", sparql},
                        {"default-graph-uri", impl_->config.graph},
                        {"timeout", std::to_string(limits.timeout.count())}},
                       accept, limits.timeout + std::chrono::milliseconds(1000), false);
  if (r.status != 200) impl_->refused(r, "query", limits.timeout);
  if (lower(r.headers).find("x-sql-state: s1tat") != std::string::npos)
    throw QueryTimeout("the query ran past its time bound of " +
                       std::to_string(limits.timeout.count()) + " ms");
  // Virtuoso cuts results at its ResultSetMaxRows and says so only in this header.
  auto headers = lower(r.headers);
  if (auto at = headers.find("x-sparql-maxrows:"); at != std::string::npos) {
    std::uint64_t cap = std::strtoull(headers.c_str() + at + 17, nullptr, 10);
    throw LimitExceeded("query result rows (Virtuoso's [SPARQL] ResultSetMaxRows cut the result)",
                        cap, cap + 1);
  }
  QueryResult out;
  if (graph) {
    out.kind = QueryResult::Kind::Graph;
    out.graph = std::move(r.body);
    return out;
  }
  return parse_sparql_json(r.body, limits.max_rows);
}

std::vector<std::string> VirtuosoStore::subjects(const std::string& predicate,
                                                 const std::string& object) {
  QueryLimits all;
  all.max_rows = std::numeric_limits<std::uint64_t>::max();
  auto r = query("SELECT ?s WHERE { ?s " + iri(predicate) + " " + iri(object) + " }", all);
  std::vector<std::string> out;
  out.reserve(r.rows.size());
  for (auto& row : r.rows)
    if (!row.empty() && row[0].kind == Term::Kind::Uri) out.push_back(std::move(row[0].value));
  return out;
}

void VirtuosoStore::load_rdfxml(const std::string& text, const std::string& base_uri) {
  RdfXmlLines lines;
  raptor_world* world = raptor_new_world();
  if (!world || raptor_world_open(world) != 0) throw IoError("cannot start raptor");
  std::unique_ptr<raptor_world, void (*)(raptor_world*)> own_world(world, raptor_free_world);
  raptor_world_set_log_handler(world, &lines, on_log);
  raptor_parser* parser = raptor_new_parser(world, "rdfxml");
  if (!parser) throw IoError("raptor has no RDF/XML parser");
  std::unique_ptr<raptor_parser, void (*)(raptor_parser*)> own_parser(parser, raptor_free_parser);
  raptor_parser_set_statement_handler(parser, &lines, on_statement);
  raptor_uri* base = raptor_new_uri(world, reinterpret_cast<const unsigned char*>(base_uri.c_str()));
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> own_base(base, raptor_free_uri);
  int rc = raptor_parser_parse_start(parser, base);
  if (rc == 0)
    rc = raptor_parser_parse_chunk(parser, reinterpret_cast<const unsigned char*>(text.data()),
                                   text.size(), 1);
  if (rc != 0 || !lines.error.empty())
    throw ParseError({base_uri, lines.error_line > 0 ? std::optional<std::uint64_t>(lines.error_line)
                                                     : std::nullopt,
                      std::nullopt, std::nullopt},
                     "not valid RDF/XML: " + (lines.error.empty() ? "parse failed" : lines.error));
  impl_->insert(lines.lines);
}

void VirtuosoStore::add(const std::vector<Triple>& triples) {
  std::vector<std::string> lines;
  lines.reserve(triples.size());
  for (const auto& t : triples) lines.push_back(triple_text(t));
  impl_->insert(lines);
}

void VirtuosoStore::remove_subject(const std::string& subject) {
  std::string s = iri(subject);
  impl_->update("WITH " + iri(impl_->config.graph) + " DELETE { " + s + " ?p ?o } WHERE { " + s +
                " ?p ?o }");
}

std::uint64_t VirtuosoStore::size() {
  auto r = query("SELECT (COUNT(*) AS ?n) WHERE { ?s ?p ?o }");
  if (r.rows.size() != 1 || r.rows[0].empty() || r.rows[0][0].kind != Term::Kind::Literal)
    throw IoError("Virtuoso did not count the triples of " + impl_->config.graph);
  const std::string& n = r.rows[0][0].value;
  if (n.empty() || n.size() > 19 || n.find_first_not_of("0123456789") != std::string::npos)
    throw IoError("Virtuoso counted \"" + n + "\" triples in " + impl_->config.graph);
  return std::stoull(n);
}

}  // namespace meshflow::repository
