// libFuzzer target: the .pvti index parser on arbitrary text (the piece files are not read: the
// .vti reader, which assembles them, has its own target).

#include "absl/strings/string_view.h"
#include "client/io/vti_reader.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  tetrefine::fuzz::CheckPieceSources(tetrefine::io::ParsePvtiIndex(text, "dir/input.pvti"));
  return 0;
}
