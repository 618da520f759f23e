// Binary Medit (.meshb) as libMeshb defines it. See medit_format.h for what is kept.
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/io/byte_order.h"
#include "client/io/cell_census.h"
#include "client/io/io_error.h"
#include "client/io/medit_format.h"
#include "core/huge_pages.h"

namespace tetrefine::io {
namespace {

// libMeshb keyword codes (GmfKwdCod).
constexpr int32_t kDimension = 3;
constexpr int32_t kVertices = 4;
constexpr int32_t kTetrahedra = 8;
constexpr int32_t kEnd = 54;
constexpr int32_t kLastKeyword = 1000;  // far above libMeshb's ~250 codes: beyond is corrupt

// Element keywords other than tets that carry a count: fate and name for the census.
const CellKind* OtherElementKind(int32_t keyword) {
  static const CellKind kEdge{"edge", "edges", CellFate::kSkip};
  static const CellKind kTriangle{"triangle", "triangles", CellFate::kSkip};
  static const CellKind kQuad{"quadrilateral", "quadrilaterals", CellFate::kSkip};
  static const CellKind kPrism{"prism", "prisms", CellFate::kUnsupported};
  static const CellKind kHex{"hexahedron", "hexahedra", CellFate::kUnsupported};
  static const CellKind kTetP2{"second-order tetrahedron", "second-order tetrahedra",
                               CellFate::kUnsupported};
  static const CellKind kHexQ2{"second-order hexahedron", "second-order hexahedra",
                               CellFate::kUnsupported};
  static const CellKind kPyramid{"pyramid", "pyramids", CellFate::kUnsupported};
  switch (keyword) {
    case 5:
    case 25:
      return &kEdge;
    case 6:
    case 24:
      return &kTriangle;
    case 7:
    case 27:
      return &kQuad;
    case 9:
      return &kPrism;
    case 10:
      return &kHex;
    case 30:
      return &kTetP2;
    case 33:
      return &kHexQ2;
    case 49:
      return &kPyramid;
    default:
      return nullptr;
  }
}

struct Sizes {
  size_t real;      // bytes per coordinate
  size_t integer;   // bytes per index, reference and count
  size_t position;  // bytes per next-keyword position
};

Sizes SizesOf(int version) {
  switch (version) {
    case 1:
      return {4, 4, 4};
    case 2:
      return {8, 4, 4};
    case 3:
      return {8, 4, 8};
    default:
      return {8, 8, 8};
  }
}

class MeshbReader {
 public:
  MeshbReader(absl::string_view bytes, absl::string_view path) : bytes_(bytes), path_(path) {}

  absl::StatusOr<MeshFile> Read(MeshbReadInfo* info) {
    if (bytes_.size() < 8) return Error("too short for a .meshb header (truncated?)");
    if (LoadAs<int32_t>(bytes_, 0, ByteOrder::kLittle) == 1) {
      order_ = ByteOrder::kLittle;
    } else if (LoadAs<int32_t>(bytes_, 0, ByteOrder::kBig) == 1) {
      order_ = ByteOrder::kBig;
    } else {
      return Error("not a .meshb file: the first word is not the code 1");
    }
    version_ = LoadAs<int32_t>(bytes_, 4, order_);
    if (version_ < 1 || version_ > 4) {
      return Error(absl::StrCat("version ", version_, " is not one of libMeshb's 1 to 4"));
    }
    if (info != nullptr) info->version = version_;
    sizes_ = SizesOf(version_);
    pos_ = 8;
    MeshFile file;
    CellCensus census;
    bool have_vertices = false;
    bool have_tets = false;
    bool ended = false;
    while (pos_ < bytes_.size()) {
      const size_t start = pos_;
      absl::StatusOr<int64_t> keyword = Integer(4, "a keyword code");
      if (!keyword.ok()) return keyword.status();
      if (*keyword == kEnd) {
        ended = true;
        break;
      }
      if (*keyword <= 0 || *keyword > kLastKeyword) {
        return Error(absl::StrCat("unknown keyword code ", *keyword, " at byte ", start));
      }
      absl::StatusOr<int64_t> next = Integer(sizes_.position, "a next-keyword position");
      if (!next.ok()) return next.status();
      if (*next != 0 &&
          (*next <= static_cast<int64_t>(start) || static_cast<uint64_t>(*next) > bytes_.size())) {
        return Error(absl::StrCat("keyword ", *keyword, " at byte ", start,
                                  " points to the next keyword at byte ", *next,
                                  ", outside the file (truncated or corrupt)"));
      }
      if (*keyword == kDimension) {
        absl::StatusOr<int64_t> dimension = Integer(4, "the dimension");
        if (!dimension.ok()) return dimension.status();
        if (*dimension != 3) {
          return Error(absl::StrCat("Dimension ", *dimension, ": only 3D meshes are read"));
        }
      } else if (*keyword == kVertices) {
        if (have_vertices) return Error("second Vertices keyword");
        if (absl::Status s = Vertices(file.mesh); !s.ok()) return s;
        have_vertices = true;
      } else if (*keyword == kTetrahedra) {
        // Several Tetrahedra keywords append (meshio writes one per cell block).
        if (!have_vertices) return Error("Tetrahedra before Vertices");
        if (absl::Status s = Tetrahedra(file); !s.ok()) return s;
        have_tets = true;
      } else if (const CellKind* kind = OtherElementKind(static_cast<int32_t>(*keyword))) {
        absl::StatusOr<int64_t> count = Integer(sizes_.integer, "an element count");
        if (!count.ok()) return count.status();
        if (*count < 0) return Error(absl::StrCat("negative count of ", kind->plural));
        census.Add(*kind, *count);
      }
      if (*next == 0) {
        if (*keyword != kDimension && *keyword != kVertices && *keyword != kTetrahedra) {
          return Error(absl::StrCat("keyword ", *keyword, " has no next-keyword position"));
        }
      } else {
        pos_ = static_cast<size_t>(*next);
      }
    }
    if (!ended) return Error("truncated: no End keyword");
    if (!have_vertices) return Error("no Vertices keyword (not a volume mesh?)");
    census.AddTets(static_cast<int64_t>(file.mesh.tets.size()));
    if (absl::Status s = census.Check(path_); !s.ok()) return s;
    file.skipped_cells = census.SkippedCells();
    if (!have_tets) return Error("no Tetrahedra keyword (truncated, or a surface mesh?)");
    file.label_name = "medit:ref";
    DropNonFiniteDerivedArrays(&file);
    if (absl::Status s = ValidateMeshFile(file, path_); !s.ok()) return s;
    return file;
  }

 private:
  absl::Status Error(absl::string_view problem) const { return FileError(path_, problem); }

  absl::StatusOr<int64_t> Integer(size_t width, absl::string_view what) {
    if (bytes_.size() - pos_ < width) {
      return Error(absl::StrCat("truncated at byte ", pos_, " reading ", what));
    }
    const int64_t value =
        width == 8 ? LoadAs<int64_t>(bytes_, pos_, order_) : LoadAs<int32_t>(bytes_, pos_, order_);
    pos_ += width;
    return value;
  }

  // The next `count` entries of `entry` bytes; fails before allocating when they cannot fit.
  absl::StatusOr<absl::string_view> Entries(int64_t count, size_t entry, absl::string_view what) {
    if (count < 0 || static_cast<uint64_t>(count) > (bytes_.size() - pos_) / entry) {
      return Error(absl::StrCat("declares ", count, " ", what, " but only ", bytes_.size() - pos_,
                                " bytes remain (truncated or corrupt)"));
    }
    const absl::string_view out = bytes_.substr(pos_, count * entry);
    pos_ += count * entry;
    return out;
  }

  int64_t IntAt(absl::string_view data, size_t offset) const {
    return sizes_.integer == 8 ? LoadAs<int64_t>(data, offset, order_)
                               : LoadAs<int32_t>(data, offset, order_);
  }

  absl::Status Vertices(Mesh& mesh) {
    absl::StatusOr<int64_t> count = Integer(sizes_.integer, "the vertex count");
    if (!count.ok()) return count.status();
    if (*count > (int64_t{1} << 32) - 1) return Error("too many vertices");
    const size_t entry = 3 * sizes_.real + sizes_.integer;
    absl::StatusOr<absl::string_view> data = Entries(*count, entry, "vertices");
    if (!data.ok()) return data.status();
    ReserveHuge(mesh.points, *count);
    mesh.points.resize(*count);
    for (int64_t i = 0; i < *count; ++i) {
      for (int a = 0; a < 3; ++a) {
        const size_t at = i * entry + a * sizes_.real;
        mesh.points[i][a] =
            sizes_.real == 4 ? LoadAs<float>(*data, at, order_) : LoadAs<double>(*data, at, order_);
      }
    }
    return absl::OkStatus();
  }

  absl::Status Tetrahedra(MeshFile& file) {
    absl::StatusOr<int64_t> count = Integer(sizes_.integer, "the tetrahedron count");
    if (!count.ok()) return count.status();
    const size_t entry = 5 * sizes_.integer;
    absl::StatusOr<absl::string_view> data = Entries(*count, entry, "tetrahedra");
    if (!data.ok()) return data.status();
    const int64_t v = static_cast<int64_t>(file.mesh.points.size());
    const size_t first = file.mesh.tets.size();
    file.mesh.tets.resize(first + *count);
    file.mesh.labels.resize(first + *count);
    for (int64_t i = 0; i < *count; ++i) {
      const size_t t = first + i;
      for (int k = 0; k < 4; ++k) {
        const int64_t index = IntAt(*data, i * entry + k * sizes_.integer);
        if (index < 1 || index > v) {  // Medit indices are 1-based
          return Error(absl::StrCat("tetrahedron ", t, " uses vertex ", index,
                                    ", out of range [1, ", v, "]"));
        }
        file.mesh.tets[t][k] = static_cast<uint32_t>(index - 1);
      }
      const int64_t ref = IntAt(*data, i * entry + 4 * sizes_.integer);
      if (ref < std::numeric_limits<int32_t>::min() || ref > std::numeric_limits<int32_t>::max()) {
        return Error(absl::StrCat("tetrahedron ", t, ": reference ", ref, " is not 32-bit"));
      }
      file.mesh.labels[t] = static_cast<int32_t>(ref);
    }
    return absl::OkStatus();
  }

  absl::string_view bytes_;
  absl::string_view path_;
  ByteOrder order_ = ByteOrder::kLittle;
  int version_ = 0;
  Sizes sizes_{};
  size_t pos_ = 0;
};

// Appends little-endian values of the version's sizes.
class MeshbWriter {
 public:
  explicit MeshbWriter(int version) : sizes_(SizesOf(version)) {}

  void Word(int32_t v) { AppendLittle(out_, v); }
  void Integer(int64_t v) {
    if (sizes_.integer == 8) {
      AppendLittle(out_, v);
    } else {
      AppendLittle(out_, static_cast<int32_t>(v));
    }
  }
  void Real(double v) {
    if (sizes_.real == 8) {
      AppendLittle(out_, v);
    } else {
      AppendLittle(out_, static_cast<float>(v));
    }
  }
  // A keyword, its next-keyword position (the end of its block, `block_bytes` after the
  // position word) and nothing else.
  void Keyword(int32_t code, size_t block_bytes) {
    Word(code);
    const int64_t next =
        block_bytes == 0 ? 0 : static_cast<int64_t>(out_.size() + sizes_.position + block_bytes);
    if (sizes_.position == 8) {
      AppendLittle(out_, next);
    } else {
      AppendLittle(out_, static_cast<int32_t>(next));
    }
  }
  const Sizes& sizes() const { return sizes_; }
  std::string& out() { return out_; }

 private:
  Sizes sizes_;
  std::string out_;
};

}  // namespace

absl::StatusOr<MeshFile> ParseMeshb(absl::string_view bytes, absl::string_view path,
                                    MeshbReadInfo* info) {
  return MeshbReader(bytes, path).Read(info);
}

std::string FormatMeshb(const MeshFile& file, const MeshbWriteOptions& options) {
  const Mesh& mesh = file.mesh;
  const size_t v = mesh.points.size();
  const size_t t = mesh.tets.size();
  int version = options.version;
  if (version < 1 || version > 4) {
    version = v > static_cast<size_t>(std::numeric_limits<int32_t>::max()) ? 4 : 3;
  }
  MeshbWriter w(version);
  const Sizes& s = w.sizes();
  // The exact size: the version and dimension words, four keywords (code and position), the
  // dimension, two counts, then the records. A round 64 for the first three lines was 4 bytes
  // short at version 3 and 12 at version 4, and the last keyword copied the file into a doubled
  // buffer.
  ReserveHuge(w.out(), 4 + 4 + 4 * (4 + s.position) + 4 + 2 * s.integer +
                           v * (3 * s.real + s.integer) + t * 5 * s.integer);
  w.Word(1);
  w.Word(version);
  w.Keyword(kDimension, 4);
  w.Word(3);
  w.Keyword(kVertices, s.integer + v * (3 * s.real + s.integer));
  w.Integer(static_cast<int64_t>(v));
  for (const Vec3& p : mesh.points) {
    for (double x : p) w.Real(x);
    w.Integer(0);
  }
  w.Keyword(kTetrahedra, s.integer + t * 5 * s.integer);
  w.Integer(static_cast<int64_t>(t));
  for (size_t i = 0; i < t; ++i) {
    for (uint32_t index : mesh.tets[i]) w.Integer(int64_t{index} + 1);
    w.Integer(file.mesh.labels.empty() ? 0 : file.mesh.labels[i]);
  }
  w.Keyword(kEnd, 0);
  return std::move(w.out());
}

}  // namespace tetrefine::io
