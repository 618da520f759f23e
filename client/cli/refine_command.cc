// tetrefine refine: refines a mesh in a volume through the tetrefine service (embedded in this
// process, or a tetrefine_server), prints progress and the paper's tables, writes the result.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/string_view.h"
#include "absl/strings/strip.h"
#include "client/cli/command_support.h"
#include "client/cli/commands.h"
#include "client/cli/exit_codes.h"
#include "client/cli/file_kind.h"
#include "client/cli/grpc_channel.h"
#include "client/cli/interrupt_guard.h"
#include "client/cli/mesh_placement.h"
#include "client/cli/mesh_write_flags.h"
#include "client/cli/progress.h"
#include "client/cli/refine_backend.h"
#include "client/cli/refine_report.h"
#include "client/cli/stats_json.h"
#include "client/io/file_bytes.h"
#include "client/io/mesh_io.h"
#include "client/io/pvd_writer.h"
#include "client/io/pvtu_writer.h"
#include "client/io/tetgen_format.h"
#include "core/quality.h"
#include "core/refine_options.h"
#include "core/voxel_type.h"
#include "sharding/halo_parts.h"
#include "wire/service_limits.h"

namespace tetrefine::cli {
namespace {

struct RefineSettings {
  std::string volume_path;
  std::string mesh_path;
  std::string output_path;
  std::string stats_json_path;  // empty: none
  std::string server;           // empty: embedded service
  TlsFiles tls;
  std::string token;  // --token-file's
  client::RefineRequestOptions options;
  io::MeshWriteOptions write;  // how the output files are encoded
  int threads = 0;
  int shards = 0;     // > 0: sharded over the comma-separated --server list
  bool pvtu = false;  // output_path is a .pvtu index written with one .vtu piece per shard
  bool every_iteration = false;
  bool fit_mesh_to_volume = false;
  bool quiet = false;
};

// The flag of each RefineOptions field the command line sets, so that the core's message
// ("options.max_iterations: must be >= 0, got -1") names the flag the user typed.
constexpr std::pair<absl::string_view, absl::string_view> kFlagOfField[] = {
    {"epsilon", "epsilon"},
    {"max_iterations", "max-iterations"},
    {"max_tets", "max-tets"},
    {"norm_coeff", "norm-coeff"},
    {"scheme", "scheme"},
    {"certify", "certify"},
    {"lattice_n", "lattice-n"},
    {"lattice_max_tets", "lattice-max-tets"},
    {"quality_reference", "quality-reference"},
    {"lattice_seed", "lattice-seed"},
    {"min_edge_length", "min-edge-length"},
    {"min_quality", "min-quality"},
};

absl::Status AsFlagError(const absl::Status& status) {
  for (const auto& [field, flag] : kFlagOfField) {
    const std::string prefix = absl::StrCat("options.", field, ":");
    if (absl::StartsWith(status.message(), prefix)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--", flag, ":", status.message().substr(prefix.size())));
    }
  }
  return status;
}

// Sets *out from `--flag NUMBER` when the flag is given; a number that is not finite is an error
// naming the flag.
template <typename Target>
absl::Status SetFiniteDouble(const ParsedArgs& args, std::string_view flag, Target* out) {
  if (std::optional<std::string> text = args.Get(flag)) {
    absl::StatusOr<double> x = ParseFiniteDouble(flag, *text);
    if (!x.ok()) return x.status();
    *out = *x;
  }
  return absl::OkStatus();
}

absl::Status SettingsFromArgs(const ParsedArgs& args, RefineSettings* s) {
  s->volume_path = *args.Get("volume");
  s->mesh_path = *args.Get("mesh");
  // The refinement options: parsed here, bounded by the core (ValidateRefineOptions below).
  absl::StatusOr<double> epsilon = ParseFiniteDouble("epsilon", *args.Get("epsilon"));
  if (!epsilon.ok()) return epsilon.status();
  s->options.refine.epsilon = *epsilon;
  if (auto text = args.Get("max-iterations")) {
    // The ranges are the core's (ValidateRefineOptions): an out-of-range number then reads the
    // same bound the core would give, not the integer type's.
    absl::StatusOr<int64_t> n =
        ParseInteger("max-iterations", *text, 0, std::numeric_limits<int>::max());
    if (!n.ok()) return n.status();
    s->options.refine.max_iterations = static_cast<int>(*n);
  }
  if (auto text = args.Get("max-tets")) {
    absl::StatusOr<int64_t> n = ParseInteger("max-tets", *text, 1, kMaxTetsCeiling);
    if (!n.ok()) return n.status();
    s->options.SetMaxTets(*n);
  }
  RefineOptions& refine = s->options.refine;
  for (absl::Status st :
       {SetFiniteDouble(args, "norm-coeff", &refine.norm_coeff),
        SetFiniteDouble(args, "quality-reference", &refine.quality_reference),
        // These two and --lattice-seed: request fields Python and the wire had and the command
        // line did not (a sweep could not reproduce such a Python run).
        SetFiniteDouble(args, "min-edge-length", &refine.min_edge_length),
        SetFiniteDouble(args, "min-quality", &refine.min_quality)}) {
    if (!st.ok()) return st;
  }
  if (auto text = args.Get("lattice-seed")) {
    absl::StatusOr<int64_t> n =
        ParseInteger("lattice-seed", *text, 0, std::numeric_limits<int64_t>::max());
    if (!n.ok()) return n.status();
    refine.lattice_seed = static_cast<uint64_t>(*n);
  }
  if (auto text = args.Get("threads")) {
    absl::StatusOr<int64_t> n = ParseInteger("threads", *text, 0, 4096);
    if (!n.ok()) return n.status();
    s->threads = static_cast<int>(*n);
  }
  if (auto text = args.Get("scheme")) {
    if (!ParseRefineScheme(*text, &s->options.refine.scheme)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--scheme: unknown scheme \"", *text,
                       "\" (known: ", std::string(RefineSchemeName(RefineScheme::kLongestEdge)),
                       ", ", std::string(RefineSchemeName(RefineScheme::kPaper)), ")"));
    }
  }
  s->options.refine.certify = args.Has("certify");
  if (auto text = args.Get("lattice-n")) {
    absl::StatusOr<int64_t> n = ParseInteger("lattice-n", *text, 0, 64);
    if (!n.ok()) return n.status();
    s->options.refine.lattice_n = static_cast<int>(*n);
  }
  // The lattice statistics cover a sample of this many tets on larger meshes (an independent
  // check found a sample's maximum at 0.2055 against 0.2606 over all of a 2.2 M-tet mesh,
  // 2026-11-25): a larger sample, up to every tet, is the user's to ask for. The core's 0 ("every
  // tet, up to max_tets") is not offered: with the default tet budget every service refuses it
  // for the points it could sample, which would make the flag's one special value an error.
  if (auto text = args.Get("lattice-max-tets")) {
    absl::StatusOr<int64_t> n = ParseInteger("lattice-max-tets", *text, 1, int64_t{1} << 40);
    if (!n.ok()) return n.status();
    s->options.refine.lattice_max_tets = *n;
  }
  if (args.Has("clamp")) s->options.refine.outside = OutsidePolicy::kClamp;
  if (args.Has("fix-orientation")) s->options.refine.orientation = OrientationPolicy::kNormalize;
  if (absl::Status valid = ValidateRefineOptions(s->options.refine); !valid.ok()) {
    return AsFlagError(valid);
  }
  s->every_iteration = args.Has("every-iteration");
  s->fit_mesh_to_volume = args.Has("fit-mesh-to-volume");
  s->quiet = args.Has("quiet");
  s->server = args.Get("server").value_or("");
  if (args.Has("server") && s->server.empty()) {
    return absl::InvalidArgumentError("--server: empty address");
  }
  // Several servers mean sharding: one part per server unless --shards says how many.
  const bool server_list = s->server.find(',') != std::string::npos;
  if (auto text = args.Get("shards")) {
    absl::StatusOr<int64_t> n = ParseInteger("shards", *text, 1, 4096);
    if (!n.ok()) return n.status();
    s->shards = static_cast<int>(*n);
    if (s->server.empty()) {
      return absl::InvalidArgumentError(
          "--shards: needs --server with one or more addresses (host:port,host:port or "
          "dns:///name:port)");
    }
  } else if (server_list) {
    s->shards = static_cast<int>(std::count(s->server.begin(), s->server.end(), ',')) + 1;
  }
  if (s->shards > 0 && args.Has("every-iteration")) {
    return absl::InvalidArgumentError(
        "--every-iteration: not available with a sharded refinement (--shards or several "
        "--server addresses): parts are merged once they are done");
  }
  absl::StatusOr<io::MeshWriteOptions> write = MeshWriteOptionsFromArgs(args);
  if (!write.ok()) return write.status();
  s->write = *write;
  absl::StatusOr<TlsFiles> tls = TlsFilesFromArgs(args);
  if (!tls.ok()) return tls.status();
  s->tls = *tls;
  if (s->tls.enabled() && s->server.empty()) {
    return absl::InvalidArgumentError(
        "--tls/--tls-ca/--tls-cert/--tls-key apply to --server; the embedded service needs "
        "none");
  }
  absl::StatusOr<std::string> token = TokenFromArgs(args);
  if (!token.ok()) return token.status();
  s->token = *token;
  if (!s->token.empty() && s->server.empty()) {
    return absl::InvalidArgumentError(
        "--token-file applies to --server; the embedded service needs none");
  }
  s->output_path =
      args.Get("output").value_or(absl::StrCat(FileStem(s->mesh_path), ".refined.vtu"));
  // A .pvtu output, or --pvtu beside another name: the result in pieces, one per shard.
  s->pvtu = args.Has("pvtu") || absl::EndsWithIgnoreCase(s->output_path, ".pvtu");
  if (s->pvtu) {
    if (!absl::EndsWithIgnoreCase(s->output_path, ".pvtu")) {
      s->output_path = absl::StrCat(PathStem(s->output_path), ".pvtu");
    }
    if (s->shards == 0) {
      return absl::InvalidArgumentError(absl::StrCat(
          args.Has("pvtu") ? "--pvtu" : "--output", ": a .pvtu holds one piece per shard; it ",
          "needs a sharded run (--shards K with --server, or several --server addresses)"));
    }
  }
  absl::Status output = CheckOutputPath(s->output_path, "--output", /*mesh=*/!s->pvtu);
  if (!output.ok()) return output;
  s->stats_json_path = args.Get("stats-json").value_or("");
  if (args.Has("stats-json")) {
    absl::Status stats = CheckOutputPath(s->stats_json_path, "--stats-json", /*mesh=*/false);
    if (!stats.ok()) return stats;
    stats = CheckNotTheSameFile(
        {"--stats-json", s->stats_json_path},
        {{"--output", s->output_path}, {"--volume", s->volume_path}, {"--mesh", s->mesh_path}});
    if (!stats.ok()) return stats;
  }
  return absl::OkStatus();
}

// Checks what is cheap to check here, so the common mistakes get a message naming the file and
// the flag that helps, before anything is sent.
absl::Status CheckPlacement(const RefineSettings& s, const Volume& volume, const Mesh& mesh) {
  if (mesh.tets.empty()) return absl::InvalidArgumentError(absl::StrCat(s.mesh_path, ": no tets"));
  if (s.options.refine.outside != OutsidePolicy::kClamp) {
    const int64_t out = FirstVertexOutside(volume, mesh);
    if (out >= 0) {
      const Vec3& p = mesh.points[static_cast<size_t>(out)];
      // A rotated grid fills only part of its world box: a vertex inside the box can still be
      // outside, and the grid index says where.
      std::string where = absl::StrCat("world box ", FormatBox(VolumeWorldBox(volume)));
      if (!GridFillsItsWorldBox(volume)) {
        const Vec3 u = volume.ContinuousIndex(p);
        const Index3& d = volume.grid().dims;
        where = absl::StrFormat(
            "at grid index (%.4g, %.4g, %.4g), outside [0, %d] x [0, %d] x [0, %d]; the volume "
            "is oblique, and its %s only bounds the rotated grid",
            u[0], u[1], u[2], d[0] - 1, d[1] - 1, d[2] - 1, where);
      }
      // The service samples every vertex, used or not; an unused one outside is most likely
      // left over from an editor, and the fix is then different.
      const bool used = std::any_of(mesh.tets.begin(), mesh.tets.end(), [&](const Tet& t) {
        return std::find(t.begin(), t.end(), static_cast<uint32_t>(out)) != t.end();
      });
      return absl::InvalidArgumentError(absl::StrCat(
          s.mesh_path, ": vertex ", out, " at ",
          // Ten digits: with six, a vertex just outside a grid far from the origin (1e7 mm)
          // printed like the box limit it breaks (a CLI sweep).
          absl::StrFormat("(%.10g, %.10g, %.10g)", p[0], p[1], p[2]), " lies outside the volume ",
          s.volume_path, " (", where, "); ",
          used ? "use --fit-mesh-to-volume to place the mesh inside it, or --clamp"
               : "no tet uses it: remove the unused vertices from the mesh, or use --clamp"));
    }
  }
  if (s.options.refine.outside == OutsidePolicy::kClamp &&
      std::none_of(mesh.points.begin(), mesh.points.end(),
                   [&](const Vec3& p) { return volume.Contains(volume.ContinuousIndex(p)); })) {
    // Allowed (the flag says so), but every value then comes from the volume's boundary: most
    // likely a mesh in another frame or unit. Found by a CLI sweep: it "converged" in silence.
    PrintWarning(absl::StrCat("no vertex of ", s.mesh_path, " lies inside the volume ",
                              s.volume_path, ": --clamp samples every vertex on its boundary"));
  }
  if (s.options.refine.orientation != OrientationPolicy::kNormalize) {
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const Tet& k = mesh.tets[t];
      if (SignedVolume6(mesh.points[k[0]], mesh.points[k[1]], mesh.points[k[2]],
                        mesh.points[k[3]]) < 0.0) {
        return absl::InvalidArgumentError(
            absl::StrCat(s.mesh_path, ": mesh.tets[", t,
                         "] is inverted (negative volume); use --fix-orientation to flip inverted "
                         "tets"));
      }
    }
  }
  return absl::OkStatus();
}

std::string IterationPath(const std::string& output, int iteration) {
  return absl::StrFormat("%s.iter%02d%s", PathStem(output), iteration, PathExtension(output));
}

// The ParaView collection of an --every-iteration series: <output stem>.pvd beside a .vtu
// output, listing the iteration files with the iteration as time step, so that ParaView opens
// the run as one time series (issue 13: ".pvd for --every-iteration"). Other formats have no
// collection file ParaView reads: none then.
std::string SeriesPath(const std::string& output) {
  return absl::EndsWithIgnoreCase(output, ".vtu") ? PathStem(output) + ".pvd" : "";
}

// What the input file said about its labels and frame, carried to every file refine writes: the
// labels come back under the input's name, the points in the input's frame.
struct InputTags {
  std::string label_name;
  io::MeshFrame frame = io::MeshFrame::kUntagged;
  std::map<int32_t, std::string> region_names;  // kept by .msh outputs
};

io::MeshFile WithQuality(const Mesh& mesh, const InputTags& tags) {
  io::MeshFile file{.mesh = mesh, .tet_iteration = {}, .tet_quality = {}};
  file.label_name = tags.label_name;
  file.frame = tags.frame;
  file.region_names = tags.region_names;
  file.tet_quality.reserve(mesh.tets.size());
  for (const Tet& t : mesh.tets) {
    file.tet_quality.push_back(static_cast<float>(
        MeanRatio(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]])));
  }
  return file;
}

// The size of the file at `path` in bytes, or -1 when it cannot be read (progress lines only).
int64_t FileSize(const std::string& path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  return error ? -1 : static_cast<int64_t>(size);
}

// "1.6 M tets, 31 MB" for a mesh file just written or read.
std::string MeshFileSummary(const std::string& path, int64_t tets) {
  std::string text = absl::StrCat(FormatCount(tets), " tets");
  if (const int64_t bytes = FileSize(path); bytes >= 0) {
    absl::StrAppend(&text, ", ", FormatBytes(bytes));
  }
  return text;
}

// Writes `file` to `path` as `s.write` says, or stages it there (`staged`), reporting it as a
// progress phase.
absl::Status WriteMeshReported(const RefineSettings& s, Progress& progress, const std::string& path,
                               const io::MeshFile& file, io::StagedFiles* staged = nullptr) {
  progress.Begin(absl::StrCat("writing ", path));
  absl::Status written = staged != nullptr ? io::StageMesh(path, file, s.write, *staged)
                                           : io::WriteMesh(path, file, s.write);
  if (!written.ok()) {
    progress.Abandon();
    return written;
  }
  const auto tets = static_cast<int64_t>(file.mesh.tets.size());
  // A staged file is not at `path` yet: its size there would be a file of a run before.
  progress.End(staged != nullptr ? absl::StrCat(FormatCount(tets), " tets")
                                 : MeshFileSummary(path, tets));
  return absl::OkStatus();
}

// Vertices summed over `pieces` (a vertex on a boundary between pieces counts once per piece).
int64_t PieceVertices(const std::vector<sharding::RefinedMesh>& pieces) {
  int64_t n = 0;
  for (const sharding::RefinedMesh& piece : pieces) {
    n += static_cast<int64_t>(piece.mesh.points.size());
  }
  return n;
}

// Writes the sharded run's `pieces` (`tets` in all) as the .pvtu at s.output_path with one .vtu
// per piece, reported as one progress phase (sizes summed over the pieces and the index).
absl::Status WritePiecesReported(const RefineSettings& s, Progress& progress,
                                 const std::vector<io::MeshFile>& pieces, int64_t tets) {
  progress.Begin(absl::StrCat("writing ", s.output_path, " and ", pieces.size(), " pieces"));
  absl::Status written = io::WritePvtu(s.output_path, pieces, s.write.vtu);
  if (!written.ok()) {
    progress.Abandon();
    return written;
  }
  int64_t bytes = std::max<int64_t>(FileSize(s.output_path), 0);
  for (size_t k = 0; k < pieces.size(); ++k) {
    bytes += std::max<int64_t>(FileSize(io::PvtuPiecePath(s.output_path, static_cast<int>(k))), 0);
  }
  progress.End(absl::StrCat(FormatCount(tets), " tets, ", FormatBytes(bytes)));
  return absl::OkStatus();
}

// The files the run writes besides --stats-json: --output, a TetGen output's .node, the
// --every-iteration files and their .pvd, a .pvtu's pieces.
std::vector<NamedPath> FilesWritten(const RefineSettings& s) {
  std::vector<NamedPath> written = {{"--output", s.output_path}};
  if (absl::EndsWithIgnoreCase(s.output_path, ".ele")) {
    written.push_back({"the .node file of --output", io::TetgenNodePath(s.output_path)});
  }
  if (s.every_iteration) {
    for (int k = 1; k <= s.options.refine.max_iterations; ++k) {
      written.push_back({absl::StrCat("--every-iteration's file of iteration ", k),
                         IterationPath(s.output_path, k)});
    }
    if (!SeriesPath(s.output_path).empty()) {
      written.push_back({"--every-iteration's series", SeriesPath(s.output_path)});
    }
  }
  if (s.pvtu) {
    for (int k = 0; k < s.shards; ++k) {
      written.push_back(
          {absl::StrCat("piece ", k, " of --output"), io::PvtuPiecePath(s.output_path, k)});
    }
  }
  return written;
}

// No file the run writes may be an input or another output. --stats-json was checked against
// --output alone, and replaced the other files silently (an outside review: exit 0, an
// unreadable result); --output itself was never checked against the inputs, and replaced the
// input mesh, or the volume with a tet mesh, with exit 0 (a second review). The message names
// both flags, as for --stats-json.
absl::Status CheckWrittenFilesAreNoInput(const RefineSettings& s) {
  // "--output .vtu": a name that is all extension gave ".vtu.iter01", refused only after the
  // first iteration (an outside review).
  if (s.every_iteration && !io::IsWritableMeshPath(IterationPath(s.output_path, 1))) {
    return absl::InvalidArgumentError(absl::StrCat(
        s.output_path, ": --output needs a name before its extension with --every-iteration, ",
        "which writes <name>.iterNN.<extension> beside it"));
  }
  std::vector<NamedPath> inputs = {{"--volume", s.volume_path}, {"--mesh", s.mesh_path}};
  if (absl::EndsWithIgnoreCase(s.mesh_path, ".ele")) {
    inputs.push_back({"the .node file of --mesh", io::TetgenNodePath(s.mesh_path)});
  }
  const std::vector<NamedPath> written = FilesWritten(s);
  for (const NamedPath& file : written) {
    if (absl::Status same = CheckNotTheSameFile(file, inputs); !same.ok()) return same;
  }
  if (s.stats_json_path.empty()) return absl::OkStatus();
  // --volume and --mesh were checked with the flags; a .ele input's .node only here.
  inputs.insert(inputs.end(), written.begin(), written.end());
  return CheckNotTheSameFile({"--stats-json", s.stats_json_path}, inputs);
}

int RunRefinement(const RefineSettings& s) {
  if (absl::Status companion = CheckWrittenFilesAreNoInput(s); !companion.ok()) {
    return Fail(companion, kExitUsage);
  }
  Progress progress(s.quiet);
  progress.Begin(absl::StrCat("reading volume ", s.volume_path));
  absl::StatusOr<io::VolumeFile> volume = LoadVolume(s.volume_path, "--volume");
  if (!volume.ok()) {
    progress.Abandon();
    return Fail(volume.status(), kExitUsage);
  }
  {
    const Volume& v = volume->volume;
    const Index3& d = v.grid().dims;
    progress.End(absl::StrFormat(
        "%dx%dx%d %s, %s", static_cast<long long>(d[0]), static_cast<long long>(d[1]),
        static_cast<long long>(d[2]), std::string(VoxelTypeName(v.type())),
        FormatBytes(v.voxel_count() * static_cast<int64_t>(VoxelSize(v.type())))));
  }
  PrintVolumeWarnings(*volume);
  if (!s.options.refine.norm_coeff.has_value()) {
    WarnIfConstant(volume->volume.ValueRange(), s.volume_path);
  } else if (absl::Status fits = CheckNormCoeffFlag(*s.options.refine.norm_coeff, volume->volume,
                                                    s.options.refine.epsilon, s.volume_path);
             !fits.ok()) {
    // The service refuses these too, but its message names the mesh (or the volume) and the
    // wire's field; the user typed --norm-coeff (an outside review, 2026-11-28).
    return Fail(fits, kExitUsage);
  }
  progress.Begin(absl::StrCat("reading mesh ", s.mesh_path));
  absl::StatusOr<io::MeshFile> mesh_file = LoadMesh(s.mesh_path, "--mesh");
  if (!mesh_file.ok()) {
    progress.Abandon();
    return Fail(mesh_file.status(), kExitUsage);
  }
  progress.End(absl::StrCat(
      FormatCount(static_cast<int64_t>(mesh_file->mesh.points.size())), " vertices, ",
      MeshFileSummary(s.mesh_path, static_cast<int64_t>(mesh_file->mesh.tets.size()))));
  if (mesh_file->ghost_cells_skipped > 0) {
    progress.Line(absl::StrCat(s.mesh_path, ": skipped ",
                               FormatCount(mesh_file->ghost_cells_skipped),
                               " ghost cells (copies of another piece's cells, as VTK flags them; "
                               "ParaView drops them too)"));
  }
  // What the output will lack, said once the input is accepted and refined, just before it is
  // written: said up front, they came before a refusal of the input, one claiming a file was
  // "written" that never was (a file-format sweep, 2026-11-28).
  std::vector<std::string> output_warnings;
  if (!mesh_file->dropped_arrays.empty()) {
    // The refined file has the sampled values, iteration, quality and the region labels; other
    // arrays of the input have no meaning on new vertices and tets, but their loss must not be
    // silent (found by a CLI sweep).
    output_warnings.push_back(absl::StrCat(
        s.mesh_path,
        ": not carried to the output: ", absl::StrJoin(mesh_file->dropped_arrays, ", "),
        " (refine writes value, iteration, quality and the region labels)"));
  }
  if (!mesh_file->skipped_cells.empty()) {
    // Boundary triangles of a Gmsh physical surface (boundary conditions) were dropped without a
    // word (an outside review, 2026-11-29).
    output_warnings.push_back(absl::StrCat(
        s.mesh_path, ": not carried to the output: the cells that are not tetrahedra (",
        io::SkippedCellsText(*mesh_file),
        "; refine reads and writes the volume's tets only: boundary markers on surface cells "
        "are not refined)"));
  }
  const InputTags tags{.label_name = mesh_file->label_name,
                       .frame = mesh_file->frame,
                       .region_names = mesh_file->region_names};
  if (!tags.region_names.empty() && !absl::EndsWithIgnoreCase(s.output_path, ".msh")) {
    std::vector<std::string> names;
    for (const auto& [label, name] : tags.region_names) {
      names.push_back(absl::StrCat(label, " \"", name, "\""));
    }
    output_warnings.push_back(
        absl::StrCat(s.output_path, ": the region names (", absl::StrJoin(names, ", "),
                     ") are not written: only .msh keeps them; the labels are kept"));
  }
  // Found by a downstream sweep (2026-11-25): a Gmsh re-save as MSH 2.2 of label -7 beside 7
  // gave one region 7 with the -7 tets inside out.
  if (const std::vector<int32_t> negative = io::NegativeGmshLabels(s.output_path, *mesh_file);
      !negative.empty()) {
    output_warnings.push_back(absl::StrCat(
        s.output_path, ": negative labels (", absl::StrJoin(negative, ", "),
        ") are written as negative physical groups: meshio and tetrefine read them back, but "
        "Gmsh takes -L as group L with the orientation reversed (saved from Gmsh as MSH 2.2 "
        "they merge into L, inside out); .vtu and .vtk keep them as plain numbers"));
  }
  if (io::LpsTagLost(s.output_path, *mesh_file)) {
    output_warnings.push_back(absl::StrCat(
        s.output_path,
        ": written in the input's LPS coordinates, but this format has no place "
        "for the SPACE=LPS tag: RAS readers (tetrefine's too) will see it mirrored in x and y; "
        ".vtu and .vtk keep the tag"));
  }
  // Region labels (mesh.labels) go in with the mesh; every child tet inherits its parent's.
  Mesh mesh = std::move(mesh_file->mesh);
  // The service samples the volume at the vertices; values stored in the file are not inputs.
  mesh.values.clear();
  if (s.fit_mesh_to_volume) {
    absl::Status fit = FitMeshToVolume(volume->volume, &mesh);
    if (!fit.ok()) return Fail(absl::StrCat(s.mesh_path, ": ", fit.message()), kExitUsage);
  }
  absl::Status placement = CheckPlacement(s, volume->volume, mesh);
  if (!placement.ok()) return Fail(placement, kExitUsage);
  // The service refuses this too, but after the upload and in its own words
  // ("mesh_header.tet_count: ... exceeds options.max_tets"); the flag is the user's.
  if (s.options.send_max_tets &&
      static_cast<int64_t>(mesh.tets.size()) > s.options.refine.max_tets) {
    return Fail(absl::StrCat("--max-tets ", s.options.refine.max_tets, " is below the ",
                             mesh.tets.size(), " tets of ", s.mesh_path,
                             ": the budget counts the output's tets, at least the input's"),
                kExitUsage);
  }

  absl::StatusOr<std::unique_ptr<RefineBackend>> backend = ChooseBackend(
      {.server = s.server,
       .shards = s.shards,
       .tls = s.tls,
       .token = s.token,
       .threads = s.threads,
       .voxels = volume->volume.voxel_count(),
       .vertices = static_cast<int64_t>(mesh.points.size()),
       .tets = static_cast<int64_t>(mesh.tets.size()),
       .max_tets = s.options.send_max_tets ? std::optional<int64_t>(s.options.refine.max_tets)
                                           : std::nullopt,
       .max_iterations = s.options.refine.max_iterations,
       .lattice_n = s.options.refine.lattice_n,
       .lattice_max_tets = s.options.refine.lattice_max_tets});
  if (!backend.ok()) {
    // A TLS file that cannot be used is the user's input; an embedded service that does not start
    // is not.
    return Fail(backend.status(),
                backend.status().code() == absl::StatusCode::kInternal ? kExitFailed : kExitUsage);
  }
  if (!s.server.empty() && s.threads != 0) {
    PrintWarning("--threads applies to the embedded service; a server uses its own --threads");
  }
  const Index3& dims = volume->volume.grid().dims;
  if (!s.quiet) {
    std::fprintf(stderr,
                 "tetrefine: refining %s (%zu vertices, %zu tets) in %s (%lldx%lldx%lld %s) at "
                 "epsilon %g on the %s\n",
                 s.mesh_path.c_str(), mesh.points.size(), mesh.tets.size(), s.volume_path.c_str(),
                 static_cast<long long>(dims[0]), static_cast<long long>(dims[1]),
                 static_cast<long long>(dims[2]),
                 std::string(VoxelTypeName(volume->volume.type())).c_str(),
                 s.options.refine.epsilon, (*backend)->Name().c_str());
  }

  absl::Status iteration_write;
  client::RefineCallbacks callbacks;
  // The service's phases, as far as the stream shows them: the input sent, each iteration, the
  // final checks (known to be over when the result's header arrives), the result received.
  auto phase_start = std::chrono::steady_clock::now();
  std::atomic<int> iterations_seen{0};
  // Between the input sent and the result's header the stream is silent while the service
  // works; long silences get a line saying so.
  SilenceWatch silence(progress, [&](double seconds) {
    std::string next = absl::StrCat("iteration ", iterations_seen.load() + 1);
    if (s.options.refine.max_iterations <= iterations_seen.load()) next.clear();
    return absl::StrCat("the service is still working (", next, next.empty() ? "" : " or ",
                        "its final checks: the stop test",
                        s.options.refine.lattice_n > 0 ? ", the lattice check" : "", "), ",
                        FormatSeconds(seconds), " since the last line");
  });
  // The halo path (longest-edge, certify) cuts each iteration's mesh anew, into fewer parts
  // where their halos would overlap: a 450 k-tet mesh over two servers went in one part every
  // iteration while this line said two (an outside review, 2026-11-28).
  const bool halos = s.options.refine.scheme != RefineScheme::kPaper || s.options.refine.certify;
  progress.Line(s.shards == 0 ? std::string("sending the input ...")
                : halos       ? absl::StrCat("cutting each iteration's mesh into up to ", s.shards,
                                             " parts (fewer where their ", sharding::kHaloRings,
                                             "-ring halos would overlap, for the same result) and "
                                                   "sending each to its server ...")
                              : absl::StrCat("cutting the mesh into ", s.shards,
                                             " parts and sending each to its server ..."));
  // Whether the server took the whole input: a connection failure after that is not the TLS
  // mismatch WithTlsHint suggests (a server killed mid-call was blamed on TLS in a sweep).
  bool input_taken = false;
  callbacks.on_input_sent = [&](int64_t bytes) {
    input_taken = true;
    progress.Line(absl::StrCat("sent ", FormatBytes(bytes), ", ",
                               FormatSeconds(SecondsSince(phase_start)),
                               "; the service validates the input and refines"));
    phase_start = std::chrono::steady_clock::now();
    silence.Touch(/*armed=*/true);
  };
  callbacks.on_iteration = [&](const IterationStats& stats) {
    progress.Line(FormatProgressLine(stats));
    ++iterations_seen;
    phase_start = std::chrono::steady_clock::now();
    silence.Touch(/*armed=*/true);
  };
  callbacks.on_result_started = [&](int64_t vertices, int64_t tets) {
    // The stream carries no message between the last iteration and the result, so the final
    // checks are reported once over, with their time.
    std::string checks = "the stop test";
    if (s.options.refine.lattice_n > 0) {
      absl::StrAppend(&checks, " and the lattice check (order ", s.options.refine.lattice_n, ")");
    }
    silence.Touch(/*armed=*/false);
    const int iterations = iterations_seen.load();
    progress.Line(absl::StrCat("service done after ", iterations, " iteration",
                               iterations == 1 ? "" : "s", "; ", checks, " took ",
                               FormatSeconds(SecondsSince(phase_start))));
    progress.Line(absl::StrCat("receiving the refined mesh: ", FormatCount(tets), " tets, ",
                               FormatCount(vertices), " vertices ..."));
    phase_start = std::chrono::steady_clock::now();
  };
  callbacks.on_result_received = [&](int64_t bytes) {
    progress.Line(absl::StrCat("received the refined mesh: ", FormatBytes(bytes), ", ",
                               FormatSeconds(SecondsSince(phase_start))));
  };
  std::vector<io::PvdEntry> series;  // the iteration files written, for the .pvd
  // The iteration files and their .pvd are renamed into place only once the output is written:
  // a run that fails or is interrupted leaves a series of a run before as it was (an outside
  // review found an interrupted re-run's first iterations under the old .pvd, and the message
  // saying that nothing was written).
  io::StagedFiles series_files;
  if (s.every_iteration) {
    callbacks.on_mesh = [&](int iteration, const Mesh& m) {
      if (!iteration_write.ok()) return;
      const std::string path = IterationPath(s.output_path, iteration);
      iteration_write = WriteMeshReported(s, progress, path, WithQuality(m, tags), &series_files);
      series.push_back({.timestep = static_cast<double>(iteration), .file = path});
    };
  }
  // Printed even with --quiet: a server that failed mid-run is the operator's to look at.
  callbacks.on_warning = [](const std::string& message) { PrintWarning(message); };
  InterruptGuard interrupt_guard;
  callbacks.should_cancel = [&] {
    return InterruptGuard::Interrupted() != 0 || !iteration_write.ok();
  };

  const auto refine_start = std::chrono::steady_clock::now();
  // A .pvtu is written from the parts' own meshes: the result is never merged here.
  std::vector<sharding::RefinedMesh> pieces;
  absl::StatusOr<client::ClientResult> reply = [&]() -> absl::StatusOr<client::ClientResult> {
    if (!s.pvtu) return (*backend)->Refine(volume->volume, mesh, s.options, callbacks);
    absl::StatusOr<sharding::ShardedResult> sharded =
        (*backend)->RefineInPieces(volume->volume, mesh, s.options, callbacks);
    if (!sharded.ok()) return sharded.status();
    pieces = std::move(sharded->pieces);
    return std::move(sharded->reply);
  }();
  silence.Touch(/*armed=*/false);
  if (reply.ok() && s.shards > 0) {
    // Sharded runs report the combined iterations once all parts are done, and their calls'
    // phases not at all: say at least that the parts are back (and merged, unless kept).
    progress.Line(absl::StrCat("parts refined and measured",
                               s.pvtu ? ", kept as pieces: " : ", merged: ",
                               FormatCount(reply->result.final_quality.count), " tets, ",
                               FormatSeconds(SecondsSince(refine_start))));
  }
  if (!iteration_write.ok()) return Fail(iteration_write, kExitUsage);
  if (const int signal_number = InterruptGuard::Interrupted(); signal_number != 0) {
    return Fail(absl::StrCat(InterruptGuard::InterruptedBy(), "; no output written"),
                128 + signal_number);
  }
  if (!reply.ok()) {
    if (reply.status().code() == absl::StatusCode::kInvalidArgument &&
        absl::StartsWith(reply.status().message(), "options.")) {
      // An option the volume cannot serve (an epsilon below what float64 resolves on it): the
      // flag, then the volume. It was put under the mesh file's name (a service sweep).
      return Fail(absl::StrCat(AsFlagError(reply.status()).message(), " (", s.volume_path, ")"),
                  kExitUsage);
    }
    if (reply.status().code() == absl::StatusCode::kInvalidArgument) {
      // The service names the input it refuses ("mesh.points[7] ...", "volume: ..."): the file
      // is the one that holds it.
      const bool volume_error = absl::StartsWith(reply.status().message(), "volume");
      return Fail(
          absl::StrCat(volume_error ? s.volume_path : s.mesh_path, ": ", reply.status().message()),
          kExitUsage);
    }
    const absl::Status failed = input_taken ? reply.status() : WithTlsHint(reply.status(), s.tls);
    return Fail(absl::StrCat((*backend)->Name(), ": ", absl::StatusCodeToString(failed.code()),
                             ": ", failed.message()),
                kExitFailed);
  }
  RefineResult& result = reply->result;
  const int64_t piece_vertices = PieceVertices(pieces);
  // Everything that reads the result's mesh is done before the mesh moves into the file.
  const std::string report =
      FormatRefineReport(result, s.options.refine.epsilon, s.options.refine.certify);
  std::string stats_json;
  if (!s.stats_json_path.empty()) {
    RunDescription run{.volume_path = s.volume_path,
                       .mesh_path = s.mesh_path,
                       .output_path = s.output_path,
                       .backend = (*backend)->Name(),
                       .options = s.options,
                       .fit_mesh_to_volume = s.fit_mesh_to_volume,
                       .input_vertices = static_cast<int64_t>(mesh.points.size()),
                       .input_tets = static_cast<int64_t>(mesh.tets.size()),
                       .output_pieces = static_cast<int>(pieces.size()),
                       .piece_vertices = piece_vertices};
    stats_json = RefineStatsJson(run, *reply);
  }
  const int64_t out_vertices =
      s.pvtu ? piece_vertices : static_cast<int64_t>(result.mesh.points.size());
  const int64_t out_tets = result.final_quality.count;
  const size_t out_pieces = pieces.size();
  // The files to write: one per piece, or the whole result; each moves its mesh out.
  std::vector<io::MeshFile> files;
  const auto add_file = [&](Mesh& m, std::vector<int32_t>& iteration, std::vector<float>& quality) {
    io::MeshFile& file = files.emplace_back(io::MeshFile{.mesh = std::move(m),
                                                         .tet_iteration = std::move(iteration),
                                                         .tet_quality = std::move(quality)});
    file.label_name = tags.label_name;
    file.frame = tags.frame;
    file.region_names = tags.region_names;
  };
  if (s.pvtu) {
    for (sharding::RefinedMesh& piece : pieces) {
      add_file(piece.mesh, piece.tet_iteration, piece.tet_quality);
    }
    pieces.clear();
  } else {
    add_file(result.mesh, result.tet_iteration, result.tet_quality);
  }
  for (const std::string& warning : output_warnings) PrintWarning(warning);
  if (!mesh.labels.empty() && !files.empty() && files[0].mesh.labels.empty()) {
    PrintWarning(absl::StrCat((*backend)->Name(), " returned no region labels; ", s.output_path,
                              " is written without them"));
  }
  absl::Status written = s.pvtu ? WritePiecesReported(s, progress, files, out_tets)
                                : WriteMeshReported(s, progress, s.output_path, files[0]);
  // A signal while writing: a regular file is finished rather than left half-written (written
  // beside and renamed into place), a pipe's write fails; either way the run stops there, with
  // 128 + the signal (it went on to exit 0, an outside review found).
  if (const int signal_number = InterruptGuard::Interrupted(); signal_number != 0) {
    return Fail(absl::StrCat(InterruptGuard::InterruptedBy(), " while writing ", s.output_path,
                             written.ok() ? ", which was finished rather than left half-written"
                                          : absl::StrCat(" (", written.message(), ")"),
                             "; nothing else (series, statistics) was written"),
                128 + signal_number);
  }
  if (!written.ok()) return Fail(written, kExitUsage);
  const std::string series_path = s.every_iteration ? SeriesPath(s.output_path) : "";
  // No iteration ran (the input met epsilon): the series is the one mesh there is, the output,
  // so that a pipeline that opens <stem>.pvd finds it (there was no .pvd and no word, an outside
  // review found).
  const bool input_only = series.empty();
  if (!series_path.empty() && input_only)
    series.push_back({.timestep = 0.0, .file = s.output_path});
  if (!series_path.empty()) {
    const std::string directory = std::filesystem::path(series_path).parent_path().string();
    absl::Status pvd = series_files.Write(series_path, io::FormatPvd(series, directory));
    if (!pvd.ok()) return Fail(pvd, kExitUsage);
  }
  if (absl::Status committed = series_files.Commit(); !committed.ok()) {
    return Fail(committed, kExitUsage);
  }
  if (!s.stats_json_path.empty()) {
    progress.Begin(absl::StrCat("writing ", s.stats_json_path));
    absl::Status json = io::WriteFileAtomically(s.stats_json_path, stats_json);
    if (!json.ok()) {
      progress.Abandon();
      return Fail(json, kExitUsage);
    }
    progress.End(FormatBytes(static_cast<int64_t>(stats_json.size())));
  }
  std::fputs(report.c_str(), stdout);
  std::printf(
      "Wrote %s%s: %lld vertices%s, %lld tets%s\n", s.output_path.c_str(),
      s.pvtu ? absl::StrCat(" (", out_pieces, " .vtu pieces)").c_str() : "",
      static_cast<long long>(out_vertices), s.pvtu ? " over the pieces" : "",
      static_cast<long long>(out_tets),
      s.stats_json_path.empty() ? "" : absl::StrCat("; statistics in ", s.stats_json_path).c_str());
  if (!series_path.empty() && input_only) {
    std::printf("Wrote %s: no iteration ran, so the series is the output alone\n",
                series_path.c_str());
  } else if (!series_path.empty()) {
    std::printf("Wrote %s: the %zu iteration meshes as a ParaView time series\n",
                series_path.c_str(), series.size());
  }
  return kExitOk;
}

}  // namespace

const CommandSpec& RefineSpec() {
  static const CommandSpec* spec = [] {
    auto* s = new CommandSpec{
        .name = "refine",
        .summary = "Refine a tet mesh until it matches the volume within epsilon",
        .usage = "tetrefine refine --volume V --mesh M --epsilon E [flags]",
        .description =
            "Splits every edge whose midpoint error |trilinear - linear| / normCoeff exceeds\n"
            "epsilon, iteration after iteration, through the tetrefine service: embedded in\n"
            "this process, or a tetrefine_server with --server. Progress goes to stderr; the\n"
            "per-iteration tables (the paper's Tables 3-7) to stdout. The mesh must lie inside\n"
            "the volume's world box (RAS mm) with positively oriented tets, unless --clamp,\n"
            "--fit-mesh-to-volume or --fix-orientation say otherwise. Vertex values are always\n"
            "sampled from the volume. The output carries per-vertex `value` and per-tet\n"
            "`iteration` and `quality`.\n"
            "Exit: 0 done (also when a limit stopped it: see the stop reason), 1 service\n"
            "failure, 2 bad flags or input.",
        .flags =
            {
                {"volume", "FILE",
                 "volume: .nii .nii.gz .hdr .nrrd .nhdr .mha .mhd .vti .pvti .vtk, DICOM series "
                 "dir or file",
                 true},
                {"mesh", "FILE", "input tet mesh: .vtu .pvtu .vtk .msh .mesh .meshb .ele .inp",
                 true},
                {"epsilon", "E", "relative tolerance, > 0 (0.1 = 10% of normCoeff)", true},
                {"max-iterations", "N",
                 absl::StrCat("stop after N iterations (default ", RefineOptions{}.max_iterations,
                              ")")},
                {"max-tets", "N",
                 absl::StrCat("stop before an iteration that would exceed N tets (default: the "
                              "service's limit: ",
                              wire::ServiceLimits{}.max_output_tets,
                              " embedded; a server's own, smaller when its memory is, with "
                              "--server)")},
                {"scheme", "NAME",
                 absl::StrCat("which edges are split: longest-edge (the midpoint test, then "
                              "each marked face's longest edge, and the fewest more "
                              "edges where a split would flatten a tet; each tet cut by the "
                              "tiling with the best worst child: reaches epsilon with bounded "
                              "quality) or paper (the midpoint test and the paper's table alone, "
                              "as published). Default ",
                              std::string(RefineSchemeName(RefineOptions{}.scheme)))},
                {"certify", "",
                 "also refine until every lattice point of every tet is within epsilon; the "
                 "report gives the certified maximum (about twice the CPU time: the demo at "
                 "epsilon 0.05)"},
                {"lattice-n", "N",
                 absl::StrCat("order of the verification lattice, (N+1)(N+2)(N+3)/6 points a "
                              "tet; 0 skips the check (default ",
                              RefineOptions{}.lattice_n, ", the paper's 165 points)")},
                {"lattice-max-tets", "N",
                 absl::StrCat(
                     "the lattice check samples N tets of a larger mesh (default ",
                     RefineOptions{}.lattice_max_tets,
                     "); N above the output's tets checks every tet; with --server, within "
                     "that server's cap on sampled points (tetrefine_server "
                     "--max_lattice_points, 2e8 by default: 1.2 M tets at --lattice-n 8)")},
                {"lattice-seed", "N",
                 absl::StrCat("seed of the lattice check's sample (default ",
                              RefineOptions{}.lattice_seed, ")")},
                {"min-edge-length", "MM",
                 "edges shorter than this (world units) are never split (default 1/64 of the "
                 "smallest voxel spacing; 0 disables the guard)"},
                {"min-quality", "Q",
                 absl::StrCat("an iteration that would make a tet of mean-ratio quality below Q is "
                              "not applied (stop reason quality_floor); in [0, 1), default ",
                              kDefaultMinQuality,
                              ", or half the input's worst tet where that is lower")},
                {"output", "FILE",
                 "refined mesh, .vtu .vtk .msh .mesh .meshb .ele, or .pvtu with --shards (default "
                 "<mesh name>.refined.vtu "
                 "in the working directory)"},
                {"pvtu", "",
                 "with --shards K: write the result as a .pvtu index (the --output name with "
                 "the extension .pvtu) and K .vtu pieces <stem>_<k>.vtu beside it, for "
                 "ParaView's parallel reader; also chosen by an --output ending in .pvtu"},
                {"every-iteration", "",
                 "also write each iteration's mesh as <output stem>.iterNN.<ext>; with a .vtu "
                 "output, also <output stem>.pvd, the series for ParaView; not with --shards or "
                 "several --server addresses"},
                {"stats-json", "FILE", "write the statistics as JSON"},
                {"server", "HOST:PORT[,...]",
                 "use this tetrefine_server instead of the embedded service; several "
                 "addresses shard the mesh over them"},
                {"shards", "K",
                 "cut the mesh into K parts refined concurrently on the --server list (each "
                 "part sent with only the volume slab it needs); the merged mesh is the "
                 "unsharded result"},
                {"threads", "N", "worker threads of the embedded service (default 0: all cores)"},
                {"norm-coeff", "X", "normCoeff of the error (default: the volume's max - min)"},
                {"quality-reference", "Q",
                 "longest-edge keeps new tets at 0.5 Q mean ratio where it can, in (0, 1] "
                 "(default: the input's worst tet; pass the first input's when refining a "
                 "result again)"},
                {"clamp", "",
                 "sample vertices outside the volume at the nearest point of its grid, indices "
                 "clamped (for a sheared grid not always the nearest world point)"},
                {"fix-orientation", "", "flip inverted input tets instead of refusing the mesh"},
                {"fit-mesh-to-volume", "",
                 "scale and move the mesh (per axis) to fill the volume's box less one voxel "
                 "(for an oblique volume: its index box less one sample, through its affine)"},
                {"quiet", "", "no progress lines on stderr"},
            },
        .positional = ""};
    for (FlagSpec& flag : MeshWriteFlagSpecs()) s->flags.push_back(std::move(flag));
    for (FlagSpec& flag : TlsFlagSpecs()) s->flags.push_back(std::move(flag));
    s->flags.push_back(TokenFlagSpec());
    return s;
  }();
  return *spec;
}

int RunRefine(const std::vector<std::string>& args) {
  int exit_code = kExitOk;
  std::optional<ParsedArgs> parsed = ParseCommandLine(RefineSpec(), args, &exit_code);
  if (!parsed.has_value()) return exit_code;
  RefineSettings settings;
  absl::Status status = SettingsFromArgs(*parsed, &settings);
  if (!status.ok()) return Fail(status, kExitUsage);
  return RunRefinement(settings);
}

}  // namespace tetrefine::cli
