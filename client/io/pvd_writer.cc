#include "client/io/pvd_writer.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "client/io/file_bytes.h"
#include "client/io/number_text.h"
#include "client/io/xml_escape.h"

namespace tetrefine::io {
namespace {

std::string RelativeTo(const std::string& file, const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(directory.empty() ? "." : directory, ec);
  const fs::path target = fs::weakly_canonical(file, ec);
  if (ec) return file;
  const fs::path relative = target.lexically_relative(base);
  // Beneath the directory: relative; elsewhere: as given (a "../" chain would break on moves).
  if (relative.empty() || *relative.begin() == "..") return file;
  return relative.generic_string();
}

}  // namespace

std::string FormatPvd(const std::vector<PvdEntry>& entries, const std::string& pvd_directory) {
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const PvdEntry& e : entries) {
    out += "    <DataSet timestep=\"";
    AppendDouble(out, e.timestep);
    absl::StrAppend(&out, "\" group=\"\" part=\"", e.part, "\" file=\"",
                    EscapeXml(RelativeTo(e.file, pvd_directory)), "\"/>\n");
  }
  out += "  </Collection>\n</VTKFile>\n";
  return out;
}

absl::Status WritePvd(const std::string& path, const std::vector<PvdEntry>& entries) {
  const std::string directory = std::filesystem::path(path).parent_path().string();
  return WriteFileAtomically(path, FormatPvd(entries, directory));
}

}  // namespace tetrefine::io
