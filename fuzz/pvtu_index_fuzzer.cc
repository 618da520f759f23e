// libFuzzer target: the .pvtu index parser on arbitrary text (the pieces it names are not read:
// they are the user's own files, read by the .vtu reader, which has its own target).

#include "absl/strings/string_view.h"
#include "client/io/pvtu_reader.h"
#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  tetrefine::fuzz::CheckPieceSources(tetrefine::io::ParsePvtuIndex(text, "dir/input.pvtu"));
  return 0;
}
