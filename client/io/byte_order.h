#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstring>
#include <string>

#include "absl/strings/string_view.h"

namespace tetrefine::io {

enum class ByteOrder { kLittle, kBig };

inline constexpr ByteOrder kNativeOrder =
    std::endian::native == std::endian::little ? ByteOrder::kLittle : ByteOrder::kBig;

// Reverses each `width`-byte element of `data` in place (width 1: no-op).
inline void SwapEachElement(std::byte* data, size_t bytes, size_t width) {
  if (width <= 1) return;
  for (size_t i = 0; i + width <= bytes; i += width) std::reverse(data + i, data + i + width);
}

// The T stored at `bytes[offset]` in `order`. The caller guarantees offset + sizeof(T) fits.
template <typename T>
T LoadAs(absl::string_view bytes, size_t offset, ByteOrder order) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, bytes.data() + offset, sizeof(T));
  if (order != kNativeOrder) std::reverse(raw, raw + sizeof(T));
  T value;
  std::memcpy(&value, raw, sizeof(T));
  return value;
}

// Appends `value` to `out` in little-endian order.
template <typename T>
void AppendLittle(std::string& out, T value) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (kNativeOrder != ByteOrder::kLittle) std::reverse(raw, raw + sizeof(T));
  out.append(reinterpret_cast<const char*>(raw), sizeof(T));
}

}  // namespace tetrefine::io
