// The only file that includes Xerces-C.
#include "engine/workflow_parser.h"

#include <xercesc/framework/MemBufInputSource.hpp>
#include <xercesc/sax/Locator.hpp>
#include <xercesc/sax/SAXParseException.hpp>
#include <xercesc/sax2/Attributes.hpp>
#include <xercesc/sax2/DefaultHandler.hpp>
#include <xercesc/sax2/SAX2XMLReader.hpp>
#include <xercesc/sax2/XMLReaderFactory.hpp>
#include <xercesc/util/PlatformUtils.hpp>
#include <xercesc/util/SecurityManager.hpp>
#include <xercesc/util/XMLString.hpp>
#include <xercesc/validators/common/Grammar.hpp>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>

#include "engine/workflow_xsd.h"
#include "mesh/errors.h"

namespace meshflow::engine {
namespace {

using namespace xercesc;

constexpr unsigned kEntityExpansionLimit = 1000;

void initialise_xerces() {
  static std::once_flag once;
  std::call_once(once, [] { XMLPlatformUtils::Initialize(); });
}

std::string narrow(const XMLCh* text) {
  if (!text) return {};
  char* chars = XMLString::transcode(text);
  std::string out = chars ? chars : "";
  XMLString::release(&chars);
  return out;
}

std::string trim(const std::string& s) {
  auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

// Builds the model while the validating parser reads; the first error stops everything.
// Xerces reports some validation errors only at an element's end, so the handler may first
// see elements where the schema allows none (an <atomic> inside a <name>...): it owns the
// tasks being built on its own stack, never points into a vector that may grow, and ignores
// what does not fit; the document is refused anyway.
class Builder : public DefaultHandler {
 public:
  explicit Builder(std::string name) : name_(std::move(name)) {}

  void setDocumentLocator(const Locator* const locator) override { locator_ = locator; }

  void startElement(const XMLCh* const, const XMLCh* const local, const XMLCh* const,
                    const Attributes& attributes) override {
    std::string tag = narrow(local);
    Location here = where();
    text_.clear();
    if (tag == "atomic" || tag == "if" || tag == "while") {
      Open task;
      task.task.kind = tag == "atomic" ? Task::Kind::Atomic : tag == "if" ? Task::Kind::If : Task::Kind::While;
      task.task.at = here;
      task.depth = stack_.size();
      open_.push_back(std::move(task));
    } else if (tag == "body" || tag == "else") {
      if (!open_.empty()) open_.back().in_else = tag == "else";
    } else if (tag == "condition") {
      if (!open_.empty()) open_.back().task.condition.at = here;
    } else if (tag == "parameter") {
      Parameter p;
      p.at = here;
      const XMLCh* name = attributes.getValue(u"name");
      if (name) p.name = trim(narrow(name));
      if (!open_.empty()) open_.back().task.parameters.push_back(std::move(p));
    }
    stack_.push_back(tag);
  }

  void characters(const XMLCh* const chars, const XMLSize_t length) override {
    std::u16string piece(chars, chars + length);
    text_ += narrow(piece.c_str());
  }

  void endElement(const XMLCh* const, const XMLCh* const local, const XMLCh* const) override {
    std::string tag = narrow(local);
    std::string value = trim(text_);
    text_.clear();
    if (stack_.empty()) return;
    stack_.pop_back();
    std::string parent = stack_.empty() ? "" : stack_.back();
    Task* task = open_.empty() ? nullptr : &open_.back().task;
    if ((tag == "atomic" || tag == "if" || tag == "while") && !open_.empty() &&
        open_.back().depth == stack_.size()) {
      Task done = std::move(open_.back().task);
      open_.pop_back();
      Body& into = open_.empty() ? workflow_.body
                                 : open_.back().in_else ? open_.back().task.else_body : open_.back().task.body;
      into.push_back(std::move(done));
    } else if (tag == "input") {
      workflow_.input_url = value;
    } else if (!task) {
      return;
    } else if (tag == "name" && parent == "atomic") {
      task->name = value;
    } else if (tag == "name" && parent == "analysis") {
      task->condition.analysis = value;
    } else if (tag == "operator") {
      task->condition.op = value;
    } else if (tag == "value") {
      task->condition.value = value;
    } else if (tag == "parameter" && !task->parameters.empty()) {
      task->parameters.back().value = value;
    }
  }

  void error(const SAXParseException& e) override { fail(e); }
  void fatalError(const SAXParseException& e) override { fail(e); }
  void warning(const SAXParseException&) override {}

  Workflow take() { return std::move(workflow_); }

 private:
  Location where() const {
    if (!locator_) return {};
    return {static_cast<int>(locator_->getLineNumber()), static_cast<int>(locator_->getColumnNumber())};
  }
  [[noreturn]] void fail(const SAXParseException& e) {
    throw ParseError({name_, static_cast<std::uint64_t>(e.getLineNumber()),
                      static_cast<std::uint64_t>(e.getColumnNumber()), {}},
                     narrow(e.getMessage()));
  }

  // A task element not closed yet, and whether its <else> is the body being read.
  struct Open {
    Task task;
    std::size_t depth = 0;  // elements enclosing it
    bool in_else = false;
  };

  std::string name_;
  const Locator* locator_ = nullptr;
  Workflow workflow_;
  std::vector<Open> open_;
  std::vector<std::string> stack_;
  std::string text_;
};

}  // namespace

const char* workflow_xsd() { return kWorkflowXsd; }

Workflow parse_workflow(const std::string& xml, const std::string& name) {
  initialise_xerces();
  std::unique_ptr<SAX2XMLReader> reader(XMLReaderFactory::createXMLReader());
  reader->setFeature(XMLUni::fgSAX2CoreNameSpaces, true);
  reader->setFeature(XMLUni::fgSAX2CoreValidation, true);
  reader->setFeature(XMLUni::fgXercesDynamic, false);
  reader->setFeature(XMLUni::fgXercesSchema, true);
  reader->setFeature(XMLUni::fgXercesSchemaFullChecking, true);
  reader->setFeature(XMLUni::fgXercesValidationErrorAsFatal, true);
  reader->setFeature(XMLUni::fgXercesUseCachedGrammarInParse, true);
  reader->setFeature(XMLUni::fgXercesLoadSchema, false);       // no xsi:schemaLocation fetches
  reader->setFeature(XMLUni::fgXercesLoadExternalDTD, false);
  reader->setFeature(XMLUni::fgXercesSkipDTDValidation, true);
  reader->setFeature(XMLUni::fgXercesDisableDefaultEntityResolution, true);  // XXE -> fatal
  SecurityManager security;
  security.setEntityExpansionLimit(kEntityExpansionLimit);  // billion laughs -> fatal
  reader->setProperty(XMLUni::fgXercesSecurityManager, &security);

  Builder builder(name);
  reader->setContentHandler(&builder);
  reader->setErrorHandler(&builder);
  MemBufInputSource schema(reinterpret_cast<const XMLByte*>(kWorkflowXsd), std::strlen(kWorkflowXsd),
                           "workflow.xsd");
  if (!reader->loadGrammar(schema, Grammar::SchemaGrammarType, true))
    throw std::runtime_error("the built-in workflow.xsd does not load");
  reader->setFeature(XMLUni::fgXercesSchemaFullChecking, false);
  MemBufInputSource document(reinterpret_cast<const XMLByte*>(xml.data()), xml.size(), name.c_str());
  try {
    reader->parse(document);
  } catch (const XMLException& e) {
    throw ParseError({name, {}, {}, {}}, narrow(e.getMessage()));
  }
  return builder.take();
}

Workflow parse_workflow_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  return parse_workflow(text.str(), path);
}

std::vector<std::string> operations_used(const Workflow& workflow) {
  std::vector<std::string> out;
  auto add = [&](const std::string& name) {
    if (!name.empty() && std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  };
  std::function<void(const Body&)> walk = [&](const Body& body) {
    for (const Task& t : body) {
      if (t.kind == Task::Kind::Atomic) {
        add(t.name);
      } else {
        add(t.condition.analysis);
        walk(t.body);
        walk(t.else_body);
      }
    }
  };
  walk(workflow.body);
  return out;
}

}  // namespace meshflow::engine
