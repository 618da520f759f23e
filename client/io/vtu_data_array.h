#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "client/io/byte_order.h"
#include "client/io/vtk_compressor.h"
#include "client/io/vtk_scalar.h"
#include "pugixml.hpp"

namespace tetrefine::io {

// How a VTK XML file stores binary data (attributes of <VTKFile>).
struct VtuEncoding {
  ByteOrder order = ByteOrder::kLittle;
  size_t header_bytes = 4;  // header_type UInt32 (the default) or UInt64
  VtkCompressor compressor = VtkCompressor::kNone;
};

// The <AppendedData> section: the bytes after its '_' marker, raw or base64 text.
struct VtuAppended {
  bool present = false;
  bool base64 = false;
  absl::string_view data;
};

// Decodes the values of <DataArray> (and field-data <Array>) elements in every storage VTK
// writes: format="ascii" (text numbers), "binary" (inline base64) and "appended" (raw or base64,
// at byte/character `offset` of the appended section), each binary form either uncompressed
// ([header word: byte count][bytes]) or block-compressed ([block count][block size][last block
// size][compressed size of each block][blocks]), header words UInt32 or UInt64 in the file's
// byte order. Child elements of a DataArray (VTK's <InformationKey>) are ignored: only the
// array's own character data counts. Errors are "<path>:<line>: DataArray "<Name>" <problem>".
class VtuArrayReader {
 public:
  // `line_of` maps a node to its 1-based line in the file.
  VtuArrayReader(absl::string_view path, const VtuEncoding& encoding, const VtuAppended& appended,
                 std::function<int64_t(pugi::xml_node)> line_of)
      : path_(path), enc_(encoding), appended_(appended), line_of_(std::move(line_of)) {}

  // The `count` values of a numeric array (any type) as doubles.
  absl::StatusOr<std::vector<double>> Doubles(pugi::xml_node array, uint64_t count);
  // The `count` values as integers; floating-point values must be whole.
  absl::StatusOr<std::vector<int64_t>> Int64s(pugi::xml_node array, uint64_t count);
  // The `count` values of a numeric array with format "binary" or "appended", as stored (after
  // decompression): count * VtkScalarSize(type) bytes in the file's byte order. For readers
  // that keep the file's own type (a volume's samples) rather than converting every value.
  absl::StatusOr<std::string> StoredBytes(pugi::xml_node array, VtkScalar type, uint64_t count);
  // The bytes of a type="String" array: its strings, each ended by a NUL.
  absl::StatusOr<std::string> StringBytes(pugi::xml_node array);

  // "<path>:<line>: DataArray "<Name>" <problem>".
  absl::Status Error(pugi::xml_node array, absl::string_view problem) const;

 private:
  // The stored bytes of a binary or appended array after decompression; `expected` bytes, or
  // whatever the header says when expected < 0.
  absl::StatusOr<std::string> Bytes(pugi::xml_node array, int64_t expected);
  absl::StatusOr<std::string> Decode(pugi::xml_node array, class ByteStream& in, int64_t expected);
  uint64_t HeaderWord(absl::string_view bytes, size_t index) const;

  absl::string_view path_;
  VtuEncoding enc_;
  VtuAppended appended_;
  std::function<int64_t(pugi::xml_node)> line_of_;
};

}  // namespace tetrefine::io
