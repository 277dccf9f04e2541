// Mesh files through OpenMesh IO: read into a polygon mesh, fan-triangulate into plain arrays.
#include "shared/mesh_io.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "shared/input_error.h"

namespace ag {
namespace {

using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

constexpr const char* kFormats[] = {".obj", ".ply", ".off", ".stl"};
constexpr const char* kFormatList = ".obj, .ply, .off or .stl";

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool supported(const std::string& ext) {
    return std::find_if(std::begin(kFormats), std::end(kFormats),
                        [&](const char* f) { return ext == f; }) != std::end(kFormats);
}

// OpenMesh refuses faces with a repeated vertex and only prints that; counting them lets the
// degenerate-triangle warning account for every face the file had.
class CountingImporter : public OpenMesh::IO::ImporterT<PolyMesh> {
public:
    using ImporterT::ImporterT;
    int rejected = 0;
    OpenMesh::FaceHandle add_face(const VHandles& indices) override {
        const OpenMesh::FaceHandle fh = ImporterT::add_face(indices);
        if (!fh.is_valid()) ++rejected;
        return fh;
    }
    using ImporterT::add_face;
};

// OpenMesh reports on its error stream (omerr) and notes every face at a non-manifold vertex
// ("complex vertex") before its importer re-adds it with vertices of its own: thousands of lines
// for the conference room, burying everything else. The stream is off while a file is read (no
// reconnecting: OpenMesh leaks its stream targets on disconnect); a file it cannot read gets the
// error below, and the pre-validation above it names the line or byte of most defects.
class QuietOpenMeshReader {
public:
    QuietOpenMeshReader() : was_enabled_(omerr().is_enabled()) { omerr().disable(); }
    ~QuietOpenMeshReader() {
        if (was_enabled_) omerr().enable();
    }
    QuietOpenMeshReader(const QuietOpenMeshReader&) = delete;
    QuietOpenMeshReader& operator=(const QuietOpenMeshReader&) = delete;

private:
    bool was_enabled_;
};

// ---- pre-validation ----------------------------------------------------------------------------
// OpenMesh trusts header counts (it reserves them and loops until they are read), so a bad count
// hangs or allocates gigabytes before any message. Every count is walked here first, bounded by
// the file's size, and a bad one is an InputError naming the line or byte.

constexpr size_t kMaxHeaderBytes = size_t(1) << 16;

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// Whitespace tokens with their line numbers, from `pos` on.
class Tokens {
public:
    Tokens(const std::string& text, size_t pos, int line) : text_(text), pos_(pos), line_(line) {}
    bool next(std::string_view& token) {
        while (pos_ < text_.size() && std::isspace((unsigned char)text_[pos_])) {
            if (text_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= text_.size()) return false;
        const size_t start = pos_;
        while (pos_ < text_.size() && !std::isspace((unsigned char)text_[pos_])) ++pos_;
        token = std::string_view(text_).substr(start, pos_ - start);
        return true;
    }
    // The rest of the current line (for line-based formats); false at the end of the file.
    bool line(std::string_view& text) {
        if (pos_ >= text_.size()) return false;
        const size_t end = std::min(text_.find('\n', pos_), text_.size());
        text = std::string_view(text_).substr(pos_, end - pos_);
        pos_ = end + 1;
        ++line_;
        return true;
    }
    int line_number() const { return line_; }
    size_t pos() const { return pos_; }

private:
    const std::string& text_;
    size_t pos_;
    int line_;
};

std::string at_line(int line) { return "line " + std::to_string(line); }

// A non-negative integer no larger than `limit`, or nullopt.
std::optional<int64_t> parse_count(std::string_view token, int64_t limit) {
    if (token.empty() || token.size() > 18) return std::nullopt;
    int64_t value = 0;
    for (const char c : token) {
        if (c < '0' || c > '9') return std::nullopt;
        value = value * 10 + (c - '0');
    }
    if (value > limit) return std::nullopt;
    return value;
}

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && std::isspace((unsigned char)line[i])) ++i;
        const size_t start = i;
        while (i < line.size() && !std::isspace((unsigned char)line[i])) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

int ply_type_size(std::string_view type) {
    if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
    if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
    if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
        type == "float32")
        return 4;
    if (type == "double" || type == "float64") return 8;
    return 0;
}

struct PlyProperty {
    int size = 0;        // scalar size, or the list's item size
    int count_size = 0;  // >0 for lists
};
struct PlyElement {
    std::string name;
    int64_t count = 0;
    int header_line = 0;
    std::vector<PlyProperty> properties;
};

void validate_ply(const std::string& path, const std::string& data) {
    if (data.compare(0, 3, "ply") != 0 || data.size() < 4 || !std::isspace((unsigned char)data[3]))
        throw_input_error(path, "line 1", "not a valid ply file: expected 'ply' as the first line");
    // The header line by line, each line exactly as OpenMesh reads it word by word: a line it
    // would read differently (a keyword it does not know, a format version that is no number, a
    // word too many or too few) once sent its reader round the same keyword forever.
    const int64_t size = int64_t(data.size());
    std::vector<PlyElement> elements;
    std::string format;
    int line_no = 0;
    size_t body = std::string::npos;
    Tokens lines(data, 0, 0);
    std::string_view line;
    while (body == std::string::npos) {
        if (lines.pos() > kMaxHeaderBytes || !lines.line(line))
            throw_input_error(path, "",
                              "PLY header has no 'end_header' within its first " +
                                  std::to_string(kMaxHeaderBytes) + " bytes");
        line_no = lines.line_number();
        const auto words = split(line);
        const auto place = at_line(line_no);
        if (line_no == 1) {
            if (words.size() != 1)
                throw_input_error(path, place, "not a valid ply file: expected 'ply' alone");
            continue;
        }
        if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
        if (words[0] == "end_header") {
            if (words.size() != 1) throw_input_error(path, place, "expected 'end_header' alone");
            body = std::min(lines.pos(), data.size());
        } else if (words[0] == "format") {
            const bool known =
                words.size() == 3 && (words[1] == "ascii" || words[1] == "binary_little_endian" ||
                                      words[1] == "binary_big_endian");
            if (!known || words[2] != "1.0")
                throw_input_error(path, place,
                                  "expected 'format ascii|binary_little_endian|binary_big_endian "
                                  "1.0'");
            format = std::string(words[1]);
        } else if (words[0] == "element") {
            if (words.size() != 3) throw_input_error(path, place, "expected 'element NAME COUNT'");
            const auto count = parse_count(words[2], size);
            if (!count)
                throw_input_error(path, place,
                                  "element count \"" + std::string(words[2]) +
                                      "\" must be a non-negative integer no larger than the "
                                      "file's size (" +
                                      std::to_string(size) + " bytes)");
            elements.push_back({std::string(words[1]), *count, line_no, {}});
        } else if (words[0] == "property") {
            if (elements.empty())
                throw_input_error(path, place, "property before any 'element' line");
            PlyProperty p;
            if (words.size() == 5 && words[1] == "list") {
                p.count_size = ply_type_size(words[2]);
                p.size = ply_type_size(words[3]);
                if (p.count_size == 0 || p.size == 0)
                    throw_input_error(path, place, "unknown PLY list type");
            } else if (words.size() == 3) {
                p.size = ply_type_size(words[1]);
                if (p.size == 0)
                    throw_input_error(path, place,
                                      "unknown PLY type \"" + std::string(words[1]) + "\"");
            } else {
                throw_input_error(path, place,
                                  "expected 'property TYPE NAME' or 'property list COUNT_TYPE "
                                  "TYPE NAME'");
            }
            elements.back().properties.push_back(p);
        } else {
            throw_input_error(path, place,
                              "unknown PLY header keyword \"" +
                                  std::string(words[0]).substr(0, 40) +
                                  "\"; expected format, element, property, comment, obj_info or "
                                  "end_header");
        }
    }
    const int64_t rest = size - int64_t(body);
    if (format == "ascii") {
        // Each value takes at least two bytes (a digit and a separator).
        Tokens tokens(data, body, line_no + 1);  // the line after end_header
        std::string_view token;
        for (const PlyElement& e : elements) {
            const int64_t values = int64_t(e.properties.size());
            if (values > 0 && e.count > rest / (2 * values))
                throw_input_error(path, at_line(e.header_line),
                                  "element '" + e.name + "' declares " + std::to_string(e.count) +
                                      " rows, more than the file's " + std::to_string(rest) +
                                      " bytes of data can hold");
            for (int64_t row = 0; row < e.count; ++row) {
                for (const PlyProperty& p : e.properties) {
                    if (!tokens.next(token))
                        throw_input_error(path, at_line(tokens.line_number()),
                                          "file ends inside element '" + e.name + "' row " +
                                              std::to_string(row) + "; expected " +
                                              std::to_string(e.count) + " rows");
                    if (p.count_size == 0) continue;
                    const auto n = parse_count(token, rest / 2);
                    if (!n)
                        throw_input_error(path, at_line(tokens.line_number()),
                                          "list count \"" + std::string(token) + "\" in element '" +
                                              e.name + "' must be a non-negative integer");
                    for (int64_t k = 0; k < *n; ++k)
                        if (!tokens.next(token))
                            throw_input_error(path, at_line(tokens.line_number()),
                                              "file ends inside a list of element '" + e.name +
                                                  "' row " + std::to_string(row));
                }
            }
        }
    } else if (format == "binary_little_endian" || format == "binary_big_endian") {
        const bool big = format == "binary_big_endian";
        int64_t pos = int64_t(body);
        for (const PlyElement& e : elements) {
            int64_t fixed = 0;
            for (const PlyProperty& p : e.properties) fixed += p.count_size ? p.count_size : p.size;
            if (fixed > 0 && e.count > (size - pos) / fixed)
                throw_input_error(path, at_line(e.header_line),
                                  "element '" + e.name + "' declares " + std::to_string(e.count) +
                                      " rows, more than the file's remaining " +
                                      std::to_string(size - pos) + " bytes can hold");
            for (int64_t row = 0; row < e.count; ++row) {
                for (const PlyProperty& p : e.properties) {
                    const int64_t start = pos;
                    pos += p.count_size ? p.count_size : p.size;
                    if (pos > size)
                        throw_input_error(path, "byte " + std::to_string(start),
                                          "file ends inside element '" + e.name + "' row " +
                                              std::to_string(row) + "; expected " +
                                              std::to_string(e.count) + " rows");
                    if (p.count_size == 0) continue;
                    int64_t n = 0;
                    for (int k = 0; k < p.count_size; ++k) {
                        const int b = (unsigned char)
                            data[size_t(big ? start + k : start + p.count_size - 1 - k)];
                        n = n * 256 + b;
                    }
                    // A 4-byte count with the top bit set is negative (or absurd) either way.
                    if (p.count_size >= 4 && n >= (int64_t(1) << 31))
                        throw_input_error(
                            path, "byte " + std::to_string(start),
                            "list count in element '" + e.name + "' is negative or too large");
                    if (n > (size - pos) / p.size)
                        throw_input_error(path, "byte " + std::to_string(start),
                                          "list count " + std::to_string(n) + " in element '" +
                                              e.name + "' runs past the end of the file");
                    pos += n * p.size;
                }
            }
        }
    } else {
        throw_input_error(path, "",
                          "PLY header has no 'format ascii|binary_little_endian|"
                          "binary_big_endian 1.0' line");
    }
}

void validate_off(const std::string& path, const std::string& data) {
    Tokens lines(data, 0, 0);
    std::string_view line;
    // Next line that is not blank or a comment; false at the end.
    auto next_line = [&](std::vector<std::string_view>& words) {
        while (lines.line(line)) {
            words = split(line.substr(0, std::min(line.find('#'), line.size())));
            if (!words.empty()) return true;
        }
        return false;
    };
    std::vector<std::string_view> words;
    if (!next_line(words) || words[0].find("OFF") == std::string_view::npos)
        throw_input_error(path, "line 1", "expected an OFF header line ('OFF')");
    // OpenMesh reads the file as binary when the six characters one past "OFF" are "BINARY",
    // whatever follows them ("OFF BINARY\xf7..." is binary to it): decide as it does, or a binary
    // header would be validated as text and its counts reach OpenMesh's reserve() unchecked.
    const size_t off = line.find("OFF");
    const bool binary = (words.size() >= 2 && words[1] == "BINARY") ||
                        (off != std::string_view::npos && line.size() >= off + 10 &&
                         line.substr(off + 4, 6) == "BINARY");
    const int64_t size = int64_t(data.size());
    if (binary) {
        // Native-endian int32 counts, float32 vertices, then "n i1 .. in" int32 faces.
        int64_t pos = int64_t(lines.pos());
        auto read_int = [&](const char* what) {
            if (pos + 4 > size)
                throw_input_error(path, "byte " + std::to_string(pos),
                                  std::string("file ends before the ") + what);
            int32_t v;
            std::memcpy(&v, data.data() + pos, 4);
            pos += 4;
            return int64_t(v);
        };
        const int64_t nv = read_int("vertex count"), nf = read_int("face count");
        read_int("edge count");
        if (nv < 0 || nf < 0 || nv > (size - pos) / 12 || nf > (size - pos) / 4)
            throw_input_error(path, "byte " + std::to_string(pos - 12),
                              "binary OFF counts (" + std::to_string(nv) + " vertices, " +
                                  std::to_string(nf) +
                                  " faces) are negative or more than the "
                                  "file's " +
                                  std::to_string(size) + " bytes can hold");
        pos += nv * 12;
        for (int64_t f = 0; f < nf; ++f) {
            const int64_t at = pos;
            const int64_t n = read_int("face list");
            if (n < 0 || n > (size - pos) / 4)
                throw_input_error(path, "byte " + std::to_string(at),
                                  "face " + std::to_string(f) + " vertex count " +
                                      std::to_string(n) + " is negative or runs past the file");
            for (int64_t k = 0; k < n; ++k) {
                const int64_t i = read_int("face's vertex index");
                if (i < 0 || i >= nv)
                    throw_input_error(path, "byte " + std::to_string(pos - 4),
                                      "vertex index " + std::to_string(i) + " out of range 0.." +
                                          std::to_string(nv - 1));
            }
        }
        return;
    }
    if (!next_line(words) || words.size() < 2)
        throw_input_error(path, at_line(lines.line_number()),
                          "expected the counts line 'VERTICES FACES EDGES'");
    const auto nv = parse_count(words[0], size / 6), nf = parse_count(words[1], size / 8);
    if (!nv || !nf)
        throw_input_error(path, at_line(lines.line_number()),
                          "counts \"" + std::string(words[0]) + " " + std::string(words[1]) +
                              "\" must be non-negative integers that the file's " +
                              std::to_string(size) + " bytes can hold");
    for (int64_t v = 0; v < *nv; ++v)
        if (!next_line(words) || words.size() < 3)
            throw_input_error(path, at_line(lines.line_number()),
                              "expected vertex " + std::to_string(v) + " of " +
                                  std::to_string(*nv) + " as 'x y z'");
    for (int64_t f = 0; f < *nf; ++f) {
        if (!next_line(words))
            throw_input_error(
                path, at_line(lines.line_number()),
                "file ends before face " + std::to_string(f) + " of " + std::to_string(*nf));
        const auto n = parse_count(words[0], int64_t(words.size()) - 1);
        if (!n)
            throw_input_error(path, at_line(lines.line_number()),
                              "expected face " + std::to_string(f) +
                                  " as 'N i1 ... iN' with N a "
                                  "non-negative integer, got \"" +
                                  std::string(words[0]) + "\"");
        for (int64_t k = 1; k <= *n; ++k)
            if (!parse_count(words[size_t(k)], *nv - 1))
                throw_input_error(path, at_line(lines.line_number()),
                                  "vertex index \"" + std::string(words[size_t(k)]) +
                                      "\" is not in 0.." + std::to_string(*nv - 1));
    }
}

void validate_stl(const std::string& path, const std::string& data) {
    const bool ascii = data.compare(0, 5, "solid") == 0 &&
                       data.find("facet", 5) != std::string::npos &&
                       data.find('\0') == std::string::npos;
    if (!ascii) {
        if (data.size() < 84)
            throw_input_error(path, "",
                              "binary STL is " + std::to_string(data.size()) +
                                  " bytes, shorter than its 84-byte header");
        uint32_t n = 0;
        std::memcpy(&n, data.data() + 80, 4);
        const uint64_t expected = 84 + 50 * uint64_t(n);
        if (expected != data.size())
            throw_input_error(path, "byte 80",
                              "binary STL declares " + std::to_string(n) + " triangles (" +
                                  std::to_string(expected) + " bytes) but the file has " +
                                  std::to_string(data.size()) + " bytes (truncated?)");
        return;
    }
    Tokens tokens(data, 0, 1);
    std::string_view token;
    int open_line = 0;
    bool ended = false;
    while (tokens.next(token)) {
        if (token == "facet") {
            if (open_line)
                throw_input_error(path, at_line(tokens.line_number()),
                                  "'facet' before the facet at " + at_line(open_line) +
                                      " was closed by 'endfacet'");
            open_line = tokens.line_number();
        } else if (token == "endfacet") {
            open_line = 0;
        } else if (token == "endsolid") {
            ended = true;
        }
    }
    if (open_line)
        throw_input_error(path, at_line(open_line),
                          "facet not closed by 'endfacet' (file truncated?)");
    if (!ended) throw_input_error(path, "", "ASCII STL does not end with 'endsolid' (truncated?)");
}

void validate_obj(const std::string& path, const std::string& data) {
    Tokens lines(data, 0, 0);
    std::string_view line;
    int64_t vertices = 0;
    while (lines.line(line)) {
        // OpenMesh trims each line before reading its keyword: " f x" is a face to it (one whose
        // vertices it could not read tripped its assertion `!vhandles.empty()`, an abort).
        line.remove_prefix(std::min(line.find_first_not_of(" \t\r\n\v\f"), line.size()));
        if (line.size() >= 2 && line[0] == 'v' && std::isspace((unsigned char)line[1])) {
            ++vertices;
        } else if (line.size() >= 2 && line[0] == 'f' && std::isspace((unsigned char)line[1])) {
            const auto words = split(line);
            for (size_t k = 1; k < words.size(); ++k) {
                const std::string_view index = words[k].substr(0, words[k].find('/'));
                int64_t i = 0;
                const bool negative = !index.empty() && index[0] == '-';
                const auto value =
                    parse_count(negative ? index.substr(1) : index, INT64_C(1) << 40);
                if (value) i = negative ? vertices + 1 - *value : *value;
                if (!value || i < 1 || i > vertices)
                    throw_input_error(path, at_line(lines.line_number()),
                                      "face refers to vertex \"" + std::string(index) +
                                          "\" but only " + std::to_string(vertices) +
                                          " vertices precede it (file truncated?)");
            }
            if (lines.pos() > data.size() && words.size() < 4)
                throw_input_error(path, at_line(lines.line_number()),
                                  "last line is cut off mid-face (file truncated?)");
        }
    }
}

void validate(const std::string& path, const std::string& ext) {
    const std::string data = read_all(path);
    if (ext == ".ply") validate_ply(path, data);
    if (ext == ".off") validate_off(path, data);
    if (ext == ".stl") validate_stl(path, data);
    if (ext == ".obj") validate_obj(path, data);
}

}  // namespace

Mesh load_mesh(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw_input_error(path, "", "cannot open mesh file: no such file");
    if (!std::filesystem::is_regular_file(path, ec))
        throw_input_error(path, "", "cannot open mesh file: not a regular file");
    const std::string ext = lower_extension(path);
    if (!supported(ext))
        throw_input_error(
            path, "",
            "unsupported mesh format \"" + ext + "\"; expected " + std::string(kFormatList));
    if (!std::ifstream(path, std::ios::binary))
        throw_input_error(path, "", "cannot open mesh file: permission denied or unreadable");

    PolyMesh poly;
    CountingImporter importer(poly);
    try {
        validate(path, ext);
        OpenMesh::IO::Options options;
        QuietOpenMeshReader quiet;
        if (!OpenMesh::IO::IOManager().read(path, importer, options))
            throw_input_error(path, "",
                              "cannot read mesh file: not a valid " + ext.substr(1) + " file");
    } catch (const std::bad_alloc&) {
        throw_input_error(path, "", "out of memory reading the mesh (a count in it is too large?)");
    } catch (const std::length_error&) {
        throw_input_error(path, "", "a count in the mesh file is too large to allocate");
    }

    Mesh mesh;
    mesh.positions.reserve(poly.n_vertices());
    for (const auto vh : poly.vertices()) {
        const auto p = poly.point(vh);
        mesh.positions.push_back({p[0], p[1], p[2]});
    }
    // Fan triangulation keeps the polygon's winding; file polygons are assumed convex.
    for (const auto fh : poly.faces()) {
        std::vector<unsigned> loop;
        for (const auto vh : poly.fv_range(fh)) loop.push_back(unsigned(vh.idx()));
        for (size_t k = 2; k < loop.size(); ++k)
            mesh.triangles.push_back({loop[0], loop[k - 1], loop[k]});
    }

    const int total = int(mesh.triangles.size()) + importer.rejected;
    if (total == 0)
        throw_input_error(path, "", "mesh has no faces; expected at least one triangle");
    const int dropped = remove_degenerate_triangles(mesh) + importer.rejected;
    if (mesh.triangles.empty())
        throw_input_error(path, "",
                          "all " + std::to_string(total) +
                              " faces are degenerate (zero area or repeated vertices)");
    if (dropped > 0)
        warn(path + ": dropped " + std::to_string(dropped) + " of " + std::to_string(total) +
             " faces as degenerate (zero area or repeated vertices)");
    return mesh;
}

void save_mesh(const Mesh& mesh, const std::string& path) {
    const std::string ext = lower_extension(path);
    if (!supported(ext))
        throw_input_error(
            path, "",
            "unsupported mesh format \"" + ext + "\"; expected " + std::string(kFormatList));
    PolyMesh poly;
    std::vector<OpenMesh::VertexHandle> handles;
    handles.reserve(mesh.positions.size());
    for (const glm::vec3& p : mesh.positions)
        handles.push_back(poly.add_vertex(PolyMesh::Point(p.x, p.y, p.z)));
    for (const glm::uvec3& t : mesh.triangles) {
        std::vector<OpenMesh::VertexHandle> face = {handles[t.x], handles[t.y], handles[t.z]};
        // Non-manifold triangles cannot join the halfedge structure; give them their own
        // vertices (as OpenMesh's importer does) so that no triangle is lost on the way out.
        if (!poly.add_face(face).is_valid()) {
            for (int k = 0; k < 3; ++k)
                face[size_t(k)] = poly.add_vertex(poly.point(face[size_t(k)]));
            poly.add_face(face);
        }
    }
    // OpenMesh logs "[OBJWriter] : write file" on every save; keep its error stream only.
    OpenMesh::mostream& log = omlog();
    const bool was_logging = log.is_enabled();
    log.disable();
    const bool written = OpenMesh::IO::write_mesh(poly, path);
    if (was_logging) log.enable();
    if (!written) throw_input_error(path, "", "cannot write mesh file (does the folder exist?)");
}

}  // namespace ag
