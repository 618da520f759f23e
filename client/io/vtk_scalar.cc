#include "client/io/vtk_scalar.h"

#include <cmath>
#include <limits>

#include "absl/strings/match.h"

namespace tetrefine::io {
namespace {

struct Names {
  VtkScalar type;
  const char* xml;
};
constexpr Names kNames[] = {
    {VtkScalar::kInt8, "Int8"},       {VtkScalar::kUInt8, "UInt8"},
    {VtkScalar::kInt16, "Int16"},     {VtkScalar::kUInt16, "UInt16"},
    {VtkScalar::kInt32, "Int32"},     {VtkScalar::kUInt32, "UInt32"},
    {VtkScalar::kInt64, "Int64"},     {VtkScalar::kUInt64, "UInt64"},
    {VtkScalar::kFloat32, "Float32"}, {VtkScalar::kFloat64, "Float64"},
};

// Calls f(T{}) with T the C++ type of `type`.
template <typename F>
auto Dispatch(VtkScalar type, F&& f) {
  switch (type) {
    case VtkScalar::kInt8:
      return f(int8_t{});
    case VtkScalar::kUInt8:
      return f(uint8_t{});
    case VtkScalar::kInt16:
      return f(int16_t{});
    case VtkScalar::kUInt16:
      return f(uint16_t{});
    case VtkScalar::kInt32:
      return f(int32_t{});
    case VtkScalar::kUInt32:
      return f(uint32_t{});
    case VtkScalar::kInt64:
      return f(int64_t{});
    case VtkScalar::kUInt64:
      return f(uint64_t{});
    case VtkScalar::kFloat32:
      return f(float{});
    case VtkScalar::kFloat64:
      break;
  }
  return f(double{});
}

// The loop is instantiated per type and per byte order so the compiler turns the memcpy of the
// native case into plain loads.
template <typename T, typename Out, typename Convert>
size_t ConvertAll(absl::string_view bytes, ByteOrder order, size_t count, Out* out,
                  Convert convert) {
  if (order == kNativeOrder) {
    for (size_t i = 0; i < count; ++i) {
      T value;
      std::memcpy(&value, bytes.data() + i * sizeof(T), sizeof(T));
      if (!convert(value, out[i])) return i;
    }
  } else {
    for (size_t i = 0; i < count; ++i) {
      if (!convert(LoadAs<T>(bytes, i * sizeof(T), order), out[i])) return i;
    }
  }
  return count;
}

}  // namespace

size_t VtkScalarSize(VtkScalar type) {
  return Dispatch(type, [](auto v) { return sizeof(v); });
}

StoredType StoredTypeOfVtk(VtkScalar type) {
  switch (type) {
    case VtkScalar::kInt8:
      return StoredType::kInt8;
    case VtkScalar::kUInt8:
      return StoredType::kUint8;
    case VtkScalar::kInt16:
      return StoredType::kInt16;
    case VtkScalar::kUInt16:
      return StoredType::kUint16;
    case VtkScalar::kInt32:
      return StoredType::kInt32;
    case VtkScalar::kUInt32:
      return StoredType::kUint32;
    case VtkScalar::kInt64:
      return StoredType::kInt64;
    case VtkScalar::kUInt64:
      return StoredType::kUint64;
    case VtkScalar::kFloat32:
      return StoredType::kFloat32;
    case VtkScalar::kFloat64:
      break;
  }
  return StoredType::kFloat64;
}

bool IsVtkInteger(VtkScalar type) {
  return Dispatch(type, [](auto v) { return std::numeric_limits<decltype(v)>::is_integer; });
}

std::optional<VtkScalar> VtkScalarFromXml(absl::string_view name) {
  for (const Names& n : kNames) {
    if (name == n.xml) return n.type;
  }
  return std::nullopt;
}

absl::string_view VtkScalarXmlName(VtkScalar type) {
  for (const Names& n : kNames) {
    if (n.type == type) return n.xml;
  }
  return "";
}

std::optional<VtkScalar> VtkScalarFromLegacy(absl::string_view name) {
  static constexpr std::pair<const char*, VtkScalar> kLegacy[] = {
      {"char", VtkScalar::kInt8},
      {"signed_char", VtkScalar::kInt8},
      {"unsigned_char", VtkScalar::kUInt8},
      {"short", VtkScalar::kInt16},
      {"unsigned_short", VtkScalar::kUInt16},
      {"int", VtkScalar::kInt32},
      {"unsigned_int", VtkScalar::kUInt32},
      {"long", VtkScalar::kInt64},
      {"unsigned_long", VtkScalar::kUInt64},
      // VTK's fixed-size names (vtkDataReader reads all eight; meshio writes vtktypeint32 and
      // friends for int32/int16/uint8 cell data, which were refused until a CLI sweep found it).
      {"vtktypeint8", VtkScalar::kInt8},
      {"vtktypeuint8", VtkScalar::kUInt8},
      {"vtktypeint16", VtkScalar::kInt16},
      {"vtktypeuint16", VtkScalar::kUInt16},
      {"vtktypeint32", VtkScalar::kInt32},
      {"vtktypeuint32", VtkScalar::kUInt32},
      {"vtktypeint64", VtkScalar::kInt64},
      {"vtktypeuint64", VtkScalar::kUInt64},
      {"vtkidtype", VtkScalar::kInt32},
      {"float", VtkScalar::kFloat32},
      {"double", VtkScalar::kFloat64},
  };
  for (const auto& [legacy, type] : kLegacy) {
    if (absl::EqualsIgnoreCase(name, legacy)) return type;
  }
  return std::nullopt;
}

void ScalarsToDoubles(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t count,
                      double* out) {
  Dispatch(type, [&](auto v) {
    using T = decltype(v);
    return ConvertAll<T>(bytes, order, count, out, [](T x, double& y) {
      y = static_cast<double>(x);
      return true;
    });
  });
}

double ScalarAt(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t index) {
  const size_t size = VtkScalarSize(type);
  double value = 0.0;
  ScalarsToDoubles(bytes.substr(index * size, size), type, order, 1, &value);
  return value;
}

size_t ScalarsToInt64s(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t count,
                       int64_t* out) {
  return Dispatch(type, [&](auto v) {
    using T = decltype(v);
    return ConvertAll<T>(bytes, order, count, out, [](T x, int64_t& y) {
      if constexpr (std::is_floating_point_v<T>) {
        // Beyond 2^62 a double is not an index anyone writes; NaN fails the comparison.
        if (!(std::abs(x) < 0x1p62) || x != std::floor(x)) return false;
        y = static_cast<int64_t>(x);
      } else if constexpr (std::is_same_v<T, uint64_t>) {
        if (x > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return false;
        y = static_cast<int64_t>(x);
      } else {
        y = x;
      }
      return true;
    });
  });
}

}  // namespace tetrefine::io
