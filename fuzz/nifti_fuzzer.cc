// libFuzzer target: the NIfTI reader (NIfTI-1 and -2, single file or .hdr/.img pair, gzip).
// The first byte picks how the rest reaches the reader: as a .nii file (gzip or not, as the
// bytes say), gzip-compressed by this target first (so the fuzzer explores headers behind a
// valid gzip layer), or split after the header into a .hdr and an .img file.

#include <algorithm>
#include <string>

#include "client/io/nifti_reader.h"
#include "client/io/zlib_codec.h"
#include "fuzz/fuzz_support.h"
#include "fuzz/volume_reader_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using tetrefine::fuzz::WritePrivateFile;
  tetrefine::fuzz::ByteSource source(data, size);
  const uint8_t mode = source.Byte() % 3;
  const std::string_view rest = source.Rest();
  std::string path;
  if (mode == 0) {
    path = WritePrivateFile("input.nii", rest);
  } else if (mode == 1) {
    absl::StatusOr<std::string> gz =
        tetrefine::io::GzipCompress(absl::string_view(rest.data(), rest.size()));
    TETREFINE_FUZZ_CHECK(gz.ok(), gz.status().ToString());
    path = WritePrivateFile("input.nii.gz", *gz);
  } else {
    // A NIfTI-2 header is 540 bytes, NIfTI-1 348: split where the bytes say it ends.
    const bool nifti2 = rest.size() >= 4 && ((rest[0] == 0x1c && rest[1] == 0x02) ||
                                             (rest[2] == 0x02 && rest[3] == 0x1c));
    const size_t split = nifti2 ? 540 : 348;
    WritePrivateFile("input.img", rest.substr(std::min(split, rest.size())));
    path = WritePrivateFile("input.hdr", rest.substr(0, split));
  }
  tetrefine::fuzz::CheckVolumeRead(tetrefine::io::ReadNifti(path));
  return 0;
}
