// libFuzzer target: the DICOM series reader on arbitrary bytes. The first two bytes choose how
// many files (1-3) the rest is cut into, in equal parts (the seeds are series of equal-size
// slices); they are written to a private directory and read as one series. The first part also
// goes through the file parser alone, whose pixel view must lie inside the bytes it was given.

#include <filesystem>
#include <string>

#include "client/io/dicom_file.h"
#include "client/io/dicom_series.h"
#include "fuzz/fuzz_support.h"
#include "fuzz/volume_reader_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tetrefine::fuzz::ByteSource in(data, size);
  const int files = in.Int(1, 3);
  const std::string_view rest = in.Rest();
  const size_t part = rest.size() / static_cast<size_t>(files);

  const std::string_view first = rest.substr(0, files == 1 ? rest.size() : part);
  const absl::StatusOr<tetrefine::io::DicomImage> image =
      tetrefine::io::ParseDicomFile(absl::string_view(first.data(), first.size()), "fuzz.dcm");
  if (image.ok() && image->pixel_data) {
    TETREFINE_FUZZ_CHECK(
        image->pixel_data->data() >= first.data() &&
            image->pixel_data->data() + image->pixel_data->size() <= first.data() + first.size(),
        "pixel data outside the file");
  } else if (!image.ok()) {
    TETREFINE_FUZZ_CHECK(!image.status().message().empty(), "an error without a message");
  }

  const std::filesystem::path probe = tetrefine::fuzz::WritePrivateFile("probe", "");
  const std::filesystem::path dir = probe.parent_path() / "series";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  for (int f = 0; f < files; ++f) {
    const std::string_view bytes =
        f + 1 == files ? rest.substr(f * part) : rest.substr(f * part, part);
    tetrefine::fuzz::WritePrivateFile("series/s" + std::to_string(f), bytes);
  }
  tetrefine::fuzz::CheckVolumeRead(tetrefine::io::ReadDicomSeries(dir.string()));
  return 0;
}
