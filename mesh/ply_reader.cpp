// PLY reader: ascii, binary little and big endian; any scalar types; extra properties and
// unknown elements skipped; polygon faces fan-triangulated; the `tristrips` element expanded.
#include <bit>
#include <cmath>
#include <cstring>

#include "mesh/readers.h"

namespace meshflow::mesh {
namespace {

enum class Encoding { Ascii, BinaryLE, BinaryBE };
enum class Scalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool scalar_from_name(std::string_view name, Scalar& out) {
  static const std::pair<std::string_view, Scalar> names[] = {
      {"char", Scalar::Int8},     {"int8", Scalar::Int8},       {"uchar", Scalar::UInt8},
      {"uint8", Scalar::UInt8},   {"short", Scalar::Int16},     {"int16", Scalar::Int16},
      {"ushort", Scalar::UInt16}, {"uint16", Scalar::UInt16},   {"int", Scalar::Int32},
      {"int32", Scalar::Int32},   {"uint", Scalar::UInt32},     {"uint32", Scalar::UInt32},
      {"float", Scalar::Float32}, {"float32", Scalar::Float32}, {"double", Scalar::Float64},
      {"float64", Scalar::Float64}};
  for (auto& [n, s] : names)
    if (n == name) {
      out = s;
      return true;
    }
  return false;
}

std::size_t scalar_size(Scalar s) {
  switch (s) {
    case Scalar::Int8: case Scalar::UInt8: return 1;
    case Scalar::Int16: case Scalar::UInt16: return 2;
    case Scalar::Int32: case Scalar::UInt32: case Scalar::Float32: return 4;
    case Scalar::Float64: return 8;
  }
  return 1;
}

bool is_integer(Scalar s) { return s != Scalar::Float32 && s != Scalar::Float64; }

const char* scalar_name(Scalar s) {
  switch (s) {
    case Scalar::Int8: return "char";
    case Scalar::UInt8: return "uchar";
    case Scalar::Int16: return "short";
    case Scalar::UInt16: return "ushort";
    case Scalar::Int32: return "int";
    case Scalar::UInt32: return "uint";
    case Scalar::Float32: return "float";
    case Scalar::Float64: return "double";
  }
  return "?";
}

// Whether an integer read from ASCII text fits the property's declared integer type.
bool fits(Scalar s, std::int64_t v) {
  switch (s) {
    case Scalar::Int8: return v >= -128 && v <= 127;
    case Scalar::UInt8: return v >= 0 && v <= 255;
    case Scalar::Int16: return v >= -32768 && v <= 32767;
    case Scalar::UInt16: return v >= 0 && v <= 65535;
    case Scalar::Int32: return v >= -2147483648ll && v <= 2147483647ll;
    case Scalar::UInt32: return v >= 0 && v <= 4294967295ll;
    default: return true;
  }
}

struct Property {
  std::string name;
  bool is_list = false;
  Scalar count_type = Scalar::UInt8;
  Scalar type = Scalar::Float32;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  std::uint64_t header_line = 0;
  bool fixed_size() const {
    for (auto& p : properties)
      if (p.is_list) return false;
    return true;
  }
  std::size_t record_size() const {
    std::size_t size = 0;
    for (auto& p : properties) size += scalar_size(p.type);
    return size;
  }
  int find(std::string_view n) const {
    for (std::size_t i = 0; i < properties.size(); ++i)
      if (properties[i].name == n) return static_cast<int>(i);
    return -1;
  }
};

template <typename T>
T load(const char* p, bool swap) {
  T value;
  std::memcpy(&value, p, sizeof value);
  if (swap) {
    if constexpr (sizeof(T) == 2) {
      auto u = std::bit_cast<std::uint16_t>(value);
      value = std::bit_cast<T>(static_cast<std::uint16_t>((u >> 8) | (u << 8)));
    } else if constexpr (sizeof(T) == 4) {
      value = std::bit_cast<T>(__builtin_bswap32(std::bit_cast<std::uint32_t>(value)));
    } else if constexpr (sizeof(T) == 8) {
      value = std::bit_cast<T>(__builtin_bswap64(std::bit_cast<std::uint64_t>(value)));
    }
  }
  return value;
}

double decode(Scalar s, const char* p, bool swap) {
  switch (s) {
    case Scalar::Int8: return static_cast<std::int8_t>(*p);
    case Scalar::UInt8: return static_cast<std::uint8_t>(*p);
    case Scalar::Int16: return load<std::int16_t>(p, swap);
    case Scalar::UInt16: return load<std::uint16_t>(p, swap);
    case Scalar::Int32: return load<std::int32_t>(p, swap);
    case Scalar::UInt32: return load<std::uint32_t>(p, swap);
    case Scalar::Float32: return load<float>(p, swap);
    case Scalar::Float64: return load<double>(p, swap);
  }
  return 0;
}

// Reads whitespace-separated tokens across lines, remembering the line of each.
class AsciiTokens {
 public:
  explicit AsciiTokens(InputStream& in) : in_(in) {}
  // The next token of record `record` of element `element` (named in the error at the end).
  std::string_view next(const std::string& element, std::uint64_t record, std::uint64_t count) {
    for (;;) {
      std::string_view token = next_token(line_);
      if (!token.empty()) return token;
      if (!in_.next_line(line_))
        in_.fail_line("unexpected end of file in element " + element + " " + std::to_string(record) + " of " +
                      std::to_string(count) + ": expected more values");
    }
  }
  // The rest of the current record's line must be empty (a record is one line in practice;
  // tokens of one record may still span lines).
  bool has_more_data() {
    for (;;) {
      if (!next_token_peek().empty()) return true;
      if (!in_.next_line(line_)) return false;
    }
  }
  InputStream& in() { return in_; }

 private:
  std::string_view next_token_peek() {
    std::string_view copy = line_;
    return next_token(copy);
  }
  InputStream& in_;
  std::string_view line_;
};

struct PlyReader {
  InputStream& in;
  MeshSink& sink;
  BatchWriter out;
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::uint64_t vertex_count = 0;
  ReadInfo info;
  std::vector<Index> polygon;

  PlyReader(InputStream& input, MeshSink& s) : in(input), sink(s), out(s) {}

  [[noreturn]] void header_error(const std::string& reason) { in.fail_line(reason); }

  void parse_header() {
    std::string_view line;
    if (!in.next_line(line) || line != "ply") {
      if (in.line() == 0 && in.at_end()) in.fail_line("empty file: expected a PLY header");
      header_error("expected 'ply' as the first line");
    }
    bool has_format = false;
    for (;;) {
      if (!in.next_line(line)) header_error("unexpected end of file in the header (no end_header)");
      std::string_view rest = line;
      std::string_view keyword = next_token(rest);
      if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
      if (keyword == "format") {
        std::string_view kind = next_token(rest);
        std::string_view version = next_token(rest);
        if (kind == "ascii") encoding = Encoding::Ascii;
        else if (kind == "binary_little_endian") encoding = Encoding::BinaryLE;
        else if (kind == "binary_big_endian") encoding = Encoding::BinaryBE;
        else header_error("unknown PLY format '" + std::string(kind) + "'");
        if (version != "1.0") header_error("unsupported PLY version '" + std::string(version) + "'");
        has_format = true;
      } else if (keyword == "element") {
        Element e;
        e.name = std::string(next_token(rest));
        std::int64_t count = 0;
        if (e.name.empty() || !parse_int(next_token(rest), count) || count < 0)
          header_error("expected 'element NAME COUNT' with a count >= 0");
        e.count = static_cast<std::uint64_t>(count);
        e.header_line = in.line();
        elements.push_back(std::move(e));
      } else if (keyword == "property") {
        if (elements.empty()) header_error("property before any element");
        Property p;
        std::string_view type = next_token(rest);
        if (type == "list") {
          p.is_list = true;
          if (!scalar_from_name(next_token(rest), p.count_type) || !is_integer(p.count_type))
            header_error("expected an integer type for the list count");
          if (!scalar_from_name(next_token(rest), p.type))
            header_error("unknown list item type");
        } else if (!scalar_from_name(type, p.type)) {
          header_error("unknown property type '" + std::string(type) + "'");
        }
        p.name = std::string(next_token(rest));
        if (p.name.empty()) header_error("property without a name");
        elements.back().properties.push_back(std::move(p));
      } else if (keyword == "end_header") {
        break;
      } else {
        header_error("unexpected header line '" + std::string(line.substr(0, 40)) + "'");
      }
    }
    if (!has_format) header_error("no 'format' line in the header");
  }

  void check_layout() {
    bool has_vertex = false;
    for (const Element& e : elements) {
      if (e.name == "vertex") {
        has_vertex = true;
        vertex_count = e.count;
        for (const char* axis : {"x", "y", "z"}) {
          int i = e.find(axis);
          if (i < 0 || e.properties[i].is_list)
            throw ParseError({in.name(), e.header_line, {}, {}},
                             std::string("element vertex has no scalar property '") + axis + "'");
        }
        if (e.count > 0xFFFFFFFEull)
          throw ParseError({in.name(), e.header_line, {}, {}}, "more than 2^32-1 vertices");
      } else if (e.name == "face" || e.name == "tristrips") {
        int i = e.find("vertex_indices");
        if (i < 0 && e.name == "face") i = e.find("vertex_index");
        if (i < 0 || !e.properties[i].is_list || !is_integer(e.properties[i].type))
          throw ParseError({in.name(), e.header_line, {}, {}},
                           "element " + e.name + " has no integer list property 'vertex_indices'");
      }
    }
    if (!has_vertex) throw ParseError({in.name(), 1, {}, {}}, "no 'vertex' element in the header");
  }

  std::uint64_t min_record_bytes(const Element& e) const {
    if (encoding == Encoding::Ascii) return 2 * std::max<std::size_t>(1, e.properties.size());
    std::uint64_t size = 0;
    for (auto& p : e.properties) size += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
    return std::max<std::uint64_t>(1, size);
  }

  void emit_vertex(double x, double y, double z, std::uint64_t index, std::uint64_t byte) {
    Point p{static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      std::string reason = "vertex " + std::to_string(index) +
                           " has a coordinate that is not a finite float (nan, inf or out of range)";
      if (encoding == Encoding::Ascii) in.fail_line(reason);
      in.fail_byte(reason, byte);
    }
    out.vertex(p);
  }

  Index check_index(double value, std::uint64_t face, std::uint64_t byte, const char* what) {
    if (value < 0 || value >= static_cast<double>(vertex_count) || value != std::floor(value)) {
      std::string reason = std::string(what) + " " + std::to_string(face) + ": vertex index " +
                           std::to_string(static_cast<long long>(value)) + " out of range (" +
                           std::to_string(vertex_count) + " vertices)";
      if (encoding == Encoding::Ascii) in.fail_line(reason);
      in.fail_byte(reason, byte);
    }
    return static_cast<Index>(value);
  }

  void emit_polygon(std::uint64_t face, std::uint64_t byte) {
    if (polygon.size() < 3) {
      std::string reason = "face " + std::to_string(face) + " has " +
                           std::to_string(polygon.size()) + " vertices; expected at least 3";
      if (encoding == Encoding::Ascii) in.fail_line(reason);
      in.fail_byte(reason, byte);
    }
    info.faces_read++;
    if (polygon.size() > 3) info.polygons++;
    out.polygon(polygon.data(), polygon.size());
  }

  // Strip s0 s1 s2 ... with -1 restarts; odd triangles flipped; triangles with a repeated
  // index are the strip's joints and are dropped.
  void emit_strip(const std::vector<std::int64_t>& strip) {
    std::size_t run_start = 0;
    for (std::size_t i = 0; i <= strip.size(); ++i) {
      if (i < strip.size() && strip[i] != -1) continue;
      for (std::size_t k = run_start; k + 2 < i; ++k) {
        Index a = static_cast<Index>(strip[k]), b = static_cast<Index>(strip[k + 1]),
              c = static_cast<Index>(strip[k + 2]);
        if (a == b || b == c || a == c) continue;
        Triangle t = ((k - run_start) % 2 == 0) ? Triangle{a, b, c} : Triangle{b, a, c};
        out.triangle(t);
        info.faces_read++;
      }
      run_start = i + 1;
    }
  }

  // ---- ascii ----
  void read_ascii_element(AsciiTokens& tokens, const Element& e) {
    bool is_vertex = e.name == "vertex", is_face = e.name == "face", is_strip = e.name == "tristrips";
    int ix = is_vertex ? e.find("x") : -1, iy = is_vertex ? e.find("y") : -1,
        iz = is_vertex ? e.find("z") : -1;
    int il = -1;
    if (is_face) il = e.find("vertex_indices") >= 0 ? e.find("vertex_indices") : e.find("vertex_index");
    if (is_strip) il = e.find("vertex_indices");
    std::vector<std::int64_t> strip;
    for (std::uint64_t r = 0; r < e.count; ++r) {
      double xyz[3] = {0, 0, 0};
      for (int pi = 0; pi < static_cast<int>(e.properties.size()); ++pi) {
        const Property& p = e.properties[pi];
        std::uint64_t items = 1;
        if (p.is_list) {
          std::int64_t n = 0;
          std::string_view token = tokens.next(e.name, r, e.count);
          if (!parse_int(token, n) || n < 0 || !fits(p.count_type, n))
            in.fail_line("element " + e.name + " " + std::to_string(r) + ": expected a list count (" +
                         scalar_name(p.count_type) + "), found '" + std::string(token.substr(0, 20)) + "'");
          items = static_cast<std::uint64_t>(n);
          if (pi == il) {
            polygon.clear();
            strip.clear();
          }
        }
        for (std::uint64_t k = 0; k < items; ++k) {
          std::string_view token = tokens.next(e.name, r, e.count);
          double value = 0;
          bool ok;
          if (is_integer(p.type)) {
            std::int64_t v = 0;
            ok = parse_int(token, v) && fits(p.type, v);
            value = static_cast<double>(v);
          } else {
            ok = parse_float(token, value);
          }
          if (!ok)
            in.fail_line("element " + e.name + " " + std::to_string(r) + ": property '" + p.name +
                         "' expects a number (" + scalar_name(p.type) + "), found '" +
                         std::string(token.substr(0, 20)) + "'");
          if (pi == ix) xyz[0] = value;
          else if (pi == iy) xyz[1] = value;
          else if (pi == iz) xyz[2] = value;
          else if (pi == il && is_face) polygon.push_back(check_index(value, r, 0, "face"));
          else if (pi == il && is_strip) {
            if (value != -1) check_index(value, r, 0, "tristrip");
            strip.push_back(static_cast<std::int64_t>(value));
          }
        }
      }
      if (is_vertex) emit_vertex(xyz[0], xyz[1], xyz[2], r, 0);
      else if (is_face) emit_polygon(r, 0);
      else if (is_strip) emit_strip(strip);
    }
  }

  // ---- binary ----
  void read_binary_element(const Element& e) {
    bool swap = (encoding == Encoding::BinaryBE) == (std::endian::native == std::endian::little);
    bool is_vertex = e.name == "vertex", is_face = e.name == "face", is_strip = e.name == "tristrips";
    int ix = is_vertex ? e.find("x") : -1, iy = is_vertex ? e.find("y") : -1,
        iz = is_vertex ? e.find("z") : -1;
    int il = -1;
    if (is_face) il = e.find("vertex_indices") >= 0 ? e.find("vertex_indices") : e.find("vertex_index");
    if (is_strip) il = e.find("vertex_indices");
    std::vector<std::int64_t> strip;
    if (e.fixed_size()) {
      std::size_t size = e.record_size();
      // Fast path: the canonical vertex layout x, y, z as float32 little endian.
      bool plain_xyz = is_vertex && !swap && e.properties.size() == 3 && ix == 0 && iy == 1 &&
                       iz == 2 && e.properties[0].type == Scalar::Float32 &&
                       e.properties[1].type == Scalar::Float32 &&
                       e.properties[2].type == Scalar::Float32;
      std::vector<std::size_t> offsets;
      std::size_t at = 0;
      for (auto& p : e.properties) {
        offsets.push_back(at);
        at += scalar_size(p.type);
      }
      for (std::uint64_t r = 0; r < e.count; ++r) {
        std::uint64_t byte = in.offset();
        if (in.fill(size) < size)
          in.fail_byte("unexpected end of file in element " + e.name + " " + std::to_string(r) +
                           " of " + std::to_string(e.count) + ": expected " + std::to_string(size) +
                           " more bytes",
                       byte);
        const char* p = in.data();
        if (is_vertex) {
          double x, y, z;
          if (plain_xyz) {
            float f[3];
            std::memcpy(f, p, 12);
            x = f[0], y = f[1], z = f[2];
          } else {
            x = decode(e.properties[ix].type, p + offsets[ix], swap);
            y = decode(e.properties[iy].type, p + offsets[iy], swap);
            z = decode(e.properties[iz].type, p + offsets[iz], swap);
          }
          emit_vertex(x, y, z, r, byte);
        }
        in.skip(size);
      }
      return;
    }
    // Fast path: the canonical face layout, one `list uchar int|uint vertex_indices`, little
    // endian. A record that is not a triangle with indices in range takes the general path,
    // which says what is wrong with it.
    bool plain_faces = is_face && !swap && e.properties.size() == 1 && il == 0 &&
                       e.properties[0].count_type == Scalar::UInt8 &&
                       (e.properties[0].type == Scalar::Int32 || e.properties[0].type == Scalar::UInt32);
    for (std::uint64_t r = 0; r < e.count; ++r) {
      std::uint64_t record_byte = in.offset();
      if (plain_faces && in.fill(13) >= 13 && in.data()[0] == 3) {
        std::uint32_t ids[3];
        std::memcpy(ids, in.data() + 1, 12);
        if (ids[0] < vertex_count && ids[1] < vertex_count && ids[2] < vertex_count) {
          out.triangle({ids[0], ids[1], ids[2]});
          info.faces_read++;
          in.skip(13);
          continue;
        }
      }
      double xyz[3] = {0, 0, 0};
      for (int pi = 0; pi < static_cast<int>(e.properties.size()); ++pi) {
        const Property& p = e.properties[pi];
        std::uint64_t byte = in.offset();
        std::uint64_t items = 1;
        if (p.is_list) {
          std::size_t cs = scalar_size(p.count_type);
          if (in.fill(cs) < cs)
            in.fail_byte("unexpected end of file in element " + e.name + " " + std::to_string(r) +
                             " of " + std::to_string(e.count),
                         byte);
          double n = decode(p.count_type, in.data(), swap);
          if (n < 0)
            in.fail_byte("element " + e.name + " " + std::to_string(r) + ": negative list count", byte);
          items = static_cast<std::uint64_t>(n);
          in.skip(cs);
          if (pi == il) {
            polygon.clear();
            strip.clear();
          }
        }
        // In pieces: a list count is the file's word, not a size to allocate at once.
        const std::size_t is = scalar_size(p.type);
        for (std::uint64_t k = 0; k < items;) {
          const std::uint64_t piece = std::min<std::uint64_t>(items - k, std::uint64_t{1} << 16);
          const std::uint64_t need = piece * is;
          if (in.fill(need) < need)
            in.fail_byte("unexpected end of file in element " + e.name + " " + std::to_string(r) +
                             " of " + std::to_string(e.count) + ": expected " + std::to_string((items - k) * is) +
                             " more bytes",
                         in.offset());
          const char* data = in.data();
          for (std::uint64_t j = 0; j < piece; ++j) {
            if (pi == ix) xyz[0] = decode(p.type, data + j * is, swap);
            else if (pi == iy) xyz[1] = decode(p.type, data + j * is, swap);
            else if (pi == iz) xyz[2] = decode(p.type, data + j * is, swap);
            else if (pi == il) {
              double value = decode(p.type, data + j * is, swap);
              if (is_face) {
                polygon.push_back(check_index(value, r, record_byte, "face"));
              } else {
                if (value != -1) check_index(value, r, record_byte, "tristrip");
                strip.push_back(static_cast<std::int64_t>(value));
              }
            }
          }
          in.skip(need);
          k += piece;
        }
      }
      if (is_vertex) emit_vertex(xyz[0], xyz[1], xyz[2], r, record_byte);
      else if (is_face) emit_polygon(r, record_byte);
      else if (is_strip) emit_strip(strip);
    }
  }

  ReadInfo run() {
    parse_header();
    check_layout();
    std::uint64_t faces = 0;
    for (auto& e : elements)
      if (e.name == "face" || e.name == "tristrips") faces += e.count;
    sink.begin(Format::Ply, static_cast<std::int64_t>(plausible_count(in, vertex_count, 6)),
               static_cast<std::int64_t>(faces ? plausible_count(in, faces, 4) : 0));
    info.format = Format::Ply;
    info.is_binary = encoding != Encoding::Ascii;
    AsciiTokens tokens(in);
    bool vertices_done = false;
    for (const Element& e : elements) {
      bool is_faces = e.name == "face" || e.name == "tristrips";
      if (is_faces && vertices_done && !sink.wants_triangles()) break;
      if (encoding == Encoding::Ascii) read_ascii_element(tokens, e);
      else read_binary_element(e);
      if (e.name == "vertex") {
        out.flush_vertices();
        vertices_done = true;
        info.raw_vertices = e.count;
      }
    }
    out.flush();
    if (sink.wants_triangles()) {
      if (encoding == Encoding::Ascii) {
        if (tokens.has_more_data()) in.fail_line("unexpected data after the last element");
      } else if (!in.at_end()) {
        in.fail_byte("unexpected data after the last element (" + std::to_string(in.fill(1 << 20)) +
                         "+ trailing bytes)",
                     in.offset());
      }
    }
    sink.end();
    return info;
  }
};

}  // namespace

ReadInfo read_ply(InputStream& in, MeshSink& sink) { return PlyReader(in, sink).run(); }

}  // namespace meshflow::mesh
