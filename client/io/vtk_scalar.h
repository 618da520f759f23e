#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include "absl/strings/string_view.h"
#include "client/io/byte_order.h"
#include "client/io/voxel_decode.h"

namespace tetrefine::io {

// The numeric types a VTK data array can hold, as XML files ("Int32", "Float64", ...) and legacy
// files ("int", "double", "vtktypeint64", ...) name them.
enum class VtkScalar {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat32,
  kFloat64
};

// Bytes per value: 1, 2, 4 or 8.
size_t VtkScalarSize(VtkScalar type);
// The volume readers' name for the same type (DecodeVoxels widens those a Volume lacks).
StoredType StoredTypeOfVtk(VtkScalar type);
bool IsVtkInteger(VtkScalar type);

// The XML type attribute ("Int8" ... "Float64"); nullopt for anything else (e.g. "String").
std::optional<VtkScalar> VtkScalarFromXml(absl::string_view name);
absl::string_view VtkScalarXmlName(VtkScalar type);

// The legacy type token, case-insensitive: char, unsigned_char, short, unsigned_short, int,
// unsigned_int, long, unsigned_long, vtktypeint64, vtktypeuint64, vtkIdType, float, double.
// "long" is 8 bytes (what VTK writes on the LP64 systems this runs on); "vtkIdType" is 4 bytes on
// disk, as vtkDataWriter writes it. nullopt for anything else (bit, string, ...).
std::optional<VtkScalar> VtkScalarFromLegacy(absl::string_view name);

// Converts `count` values of `type` stored back to back in `bytes` (which holds at least
// count * VtkScalarSize(type) bytes) in byte order `order`, writing out[0 .. count).
void ScalarsToDoubles(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t count,
                      double* out);

// Value `index` of such bytes, as a double (for messages naming a bad value).
double ScalarAt(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t index);

// Same into int64. Floating-point values must be whole numbers within +-2^62; returns the index
// of the first value that is not (or that is an unsigned 64-bit value above INT64_MAX), or
// `count` when all converted.
size_t ScalarsToInt64s(absl::string_view bytes, VtkScalar type, ByteOrder order, size_t count,
                       int64_t* out);

}  // namespace tetrefine::io
