#include "sparql/protocol.h"

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>

namespace meshflow::sparql {
namespace {

using repository::QueryResult;
using repository::Term;

std::string trim(const std::string& s) {
  auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}
std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

nlohmann::json json_term(const Term& t) {
  nlohmann::json j;
  switch (t.kind) {
    case Term::Kind::Uri: j = {{"type", "uri"}, {"value", t.value}}; break;
    case Term::Kind::Blank: j = {{"type", "bnode"}, {"value", t.value}}; break;
    default:
      j = {{"type", "literal"}, {"value", t.value}};
      if (!t.datatype.empty()) j["datatype"] = t.datatype;
      if (!t.language.empty()) j["xml:lang"] = t.language;
  }
  return j;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string tsv_term(const Term& t) {
  switch (t.kind) {
    case Term::Kind::Unbound: return "";
    case Term::Kind::Uri: return "<" + t.value + ">";
    case Term::Kind::Blank: return "_:" + t.value;
    default: break;
  }
  std::string v = "\"";
  for (char c : t.value) {
    if (c == '"') v += "\\\"";
    else if (c == '\\') v += "\\\\";
    else if (c == '\t') v += "\\t";
    else if (c == '\n') v += "\\n";
    else if (c == '\r') v += "\\r";
    else v += c;
  }
  v += "\"";
  if (!t.language.empty()) v += "@" + t.language;
  else if (!t.datatype.empty()) v += "^^<" + t.datatype + ">";
  return v;
}

}  // namespace

std::vector<MediaRange> parse_accept(const std::string& header) {
  std::vector<MediaRange> out;
  std::size_t start = 0;
  while (start <= header.size() && out.size() < 64) {
    auto end = header.find(',', start);
    if (end == std::string::npos) end = header.size();
    std::string part = header.substr(start, end - start);
    start = end + 1;
    auto semi = part.find(';');
    MediaRange m;
    m.type = lower(trim(part.substr(0, semi)));
    if (m.type.empty() || m.type.find('/') == std::string::npos) continue;
    while (semi != std::string::npos) {
      auto next = part.find(';', semi + 1);
      std::string param = trim(part.substr(semi + 1, next == std::string::npos ? std::string::npos
                                                                              : next - semi - 1));
      if (param.size() > 2 && (param[0] == 'q' || param[0] == 'Q') && param[1] == '=') {
        try {
          std::size_t used = 0;
          double q = std::stod(param.substr(2), &used);
          m.q = (q >= 0 && q <= 1) ? q : 0;
        } catch (...) {
          m.q = 0;
        }
      }
      semi = next;
    }
    out.push_back(m);
  }
  return out;
}

std::optional<Format> choose_format(const std::string& accept_header, bool graph) {
  struct Offer { const char* type; Format format; };
  static const std::vector<Offer> results = {
      {"application/sparql-results+json", Format::Json},
      {"application/sparql-results+xml", Format::Xml},
      {"application/json", Format::Json},
      {"application/xml", Format::Xml},
      {"text/xml", Format::Xml},
      {"text/csv", Format::Csv},
      {"text/tab-separated-values", Format::Tsv}};
  static const std::vector<Offer> graphs = {
      {"text/turtle", Format::Turtle},
      {"application/rdf+xml", Format::RdfXml},
      {"application/x-turtle", Format::Turtle},
      {"application/xml", Format::RdfXml},
      {"text/xml", Format::RdfXml}};
  const auto& offers = graph ? graphs : results;
  auto ranges = parse_accept(accept_header);
  if (ranges.empty()) return offers.front().format;
  // Each offer gets the q of the most specific range matching it; the best q wins, ties go to
  // the order of `offers`.
  double best_q = 0;
  std::optional<Format> best;
  for (const auto& offer : offers) {
    std::string type = offer.type;
    std::string major = type.substr(0, type.find('/'));
    int specificity = -1;
    double q = 0;
    for (const auto& r : ranges) {
      int s = r.type == type ? 2 : r.type == major + "/*" ? 1 : r.type == "*/*" ? 0 : -1;
      if (s > specificity) { specificity = s; q = r.q; }
    }
    if (specificity >= 0 && q > best_q) { best_q = q; best = offer.format; }
  }
  return best;
}

std::string content_type(Format format) {
  switch (format) {
    case Format::Json: return "application/sparql-results+json";
    case Format::Xml: return "application/sparql-results+xml";
    case Format::Csv: return "text/csv; charset=utf-8";
    case Format::Tsv: return "text/tab-separated-values; charset=utf-8";
    case Format::Turtle: return "text/turtle; charset=utf-8";
    case Format::RdfXml: return "application/rdf+xml";
  }
  return "application/octet-stream";
}

const char* redland_graph_format(Format format) {
  return format == Format::RdfXml ? "rdfxml" : "turtle";
}

std::string write_results(const QueryResult& r, Format format) {
  bool ask = r.kind == QueryResult::Kind::Boolean;
  switch (format) {
    case Format::Json: {
      nlohmann::json j;
      j["head"] = nlohmann::json::object();
      if (ask) {
        j["boolean"] = r.boolean;
        return j.dump();
      }
      j["head"]["vars"] = r.variables;
      auto bindings = nlohmann::json::array();
      for (const auto& row : r.rows) {
        nlohmann::json b = nlohmann::json::object();
        for (std::size_t i = 0; i < row.size() && i < r.variables.size(); ++i)
          if (row[i].kind != Term::Kind::Unbound) b[r.variables[i]] = json_term(row[i]);
        bindings.push_back(std::move(b));
      }
      j["results"]["bindings"] = std::move(bindings);
      return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    }
    case Format::Xml: {
      std::string s = "<?xml version=\"1.0\"?>\n<sparql xmlns=\"http://www.w3.org/2005/sparql-results#\">\n<head>";
      if (ask) return s + "</head>\n<boolean>" + (r.boolean ? "true" : "false") + "</boolean>\n</sparql>\n";
      for (const auto& v : r.variables) s += "<variable name=\"" + xml_escape(v) + "\"/>";
      s += "</head>\n<results>\n";
      for (const auto& row : r.rows) {
        s += "<result>";
        for (std::size_t i = 0; i < row.size() && i < r.variables.size(); ++i) {
          const auto& t = row[i];
          if (t.kind == Term::Kind::Unbound) continue;
          s += "<binding name=\"" + xml_escape(r.variables[i]) + "\">";
          if (t.kind == Term::Kind::Uri) s += "<uri>" + xml_escape(t.value) + "</uri>";
          else if (t.kind == Term::Kind::Blank) s += "<bnode>" + xml_escape(t.value) + "</bnode>";
          else {
            s += "<literal";
            if (!t.language.empty()) s += " xml:lang=\"" + xml_escape(t.language) + "\"";
            else if (!t.datatype.empty()) s += " datatype=\"" + xml_escape(t.datatype) + "\"";
            s += ">" + xml_escape(t.value) + "</literal>";
          }
          s += "</binding>";
        }
        s += "</result>\n";
      }
      return s + "</results>\n</sparql>\n";
    }
    case Format::Csv:
    case Format::Tsv: {
      bool csv = format == Format::Csv;
      std::string s;
      if (ask) return csv ? std::string("_askResult\r\n") + (r.boolean ? "true" : "false") + "\r\n"
                          : std::string("?_askResult\n") + (r.boolean ? "true" : "false") + "\n";
      for (std::size_t i = 0; i < r.variables.size(); ++i)
        s += (i ? (csv ? "," : "\t") : "") + (csv ? r.variables[i] : "?" + r.variables[i]);
      s += csv ? "\r\n" : "\n";
      for (const auto& row : r.rows) {
        for (std::size_t i = 0; i < row.size(); ++i) {
          if (i) s += csv ? "," : "\t";
          if (csv) s += row[i].kind == Term::Kind::Blank ? "_:" + row[i].value : csv_field(row[i].value);
          else s += tsv_term(row[i]);
        }
        s += csv ? "\r\n" : "\n";
      }
      return s;
    }
    default:
      return "";
  }
}

bool is_update(const std::string& text) {
  static const char* updates[] = {"insert", "delete", "load", "clear", "drop", "create",
                                  "add", "move", "copy", "with"};
  std::string word = repository::sparql_first_keyword(text);
  return std::any_of(std::begin(updates), std::end(updates), [&](const char* u) { return word == u; });
}

}  // namespace meshflow::sparql
