#include "tools/reproduce/results_json.h"

#include "client/io/json_writer.h"
#include "core/configuration.h"
#include "core/lattice.h"

namespace tetrefine::reproduce {

using io::JsonWriter;
namespace {

void WriteQuality(JsonWriter& w, std::string_view key, const QualityStats& q) {
  w.Key(key);
  w.BeginObject();
  w.Field("min", q.min);
  w.Field("mean", q.mean);
  w.Field("count", q.count);
  w.EndObject();
}

void WriteMatch(JsonWriter& w, std::string_view key, const BaselineMatch& m) {
  w.Key(key);
  w.BeginObject();
  w.Field("reached", m.reached);
  w.Field("level", m.level);
  w.Field("tets", m.tets);
  w.EndObject();
}

void WriteIteration(JsonWriter& w, const IterationStats& s) {
  w.BeginObject();
  w.Field("iteration", s.iteration);
  w.Field("initial_tets", s.initial_tets);
  w.Field("final_tets", s.final_tets);
  w.Field("tets_with_error", s.tets_with_error);
  w.Field("edges", s.edges);
  w.Field("split_edges", s.split_edges);
  w.Field("short_edges_kept", s.short_edges_kept);
  w.Field("max_error", s.max_error);
  w.Field("mean_error", s.mean_error);
  w.Field("max_segment_error", s.max_segment_error);
  w.Field("closure_edges", s.closure_edges);
  w.Field("guard_edges", s.guard_edges);
  w.Field("other_tilings", s.other_tilings);
  w.Field("failing_tets", s.failing_tets);
  w.Key("configurations");
  w.BeginObject();
  for (int c = 0; c < kNumConfigurations; ++c) {
    w.Field(ConfigurationName(static_cast<Configuration>(c)), s.configurations[c]);
  }
  w.EndObject();
  w.Field("schonhardt_prisms", s.schonhardt_prisms);
  WriteQuality(w, "quality", s.quality);
  w.Field("seconds", s.seconds);
  w.EndObject();
}

void WriteLattice(JsonWriter& w, const LatticeStats& l) {
  w.Key("lattice");
  w.BeginObject();
  w.Field("n", l.n);
  w.Field("tets_sampled", l.tets_sampled);
  w.Field("points_sampled", l.points_sampled);
  w.Field("max_error", l.max_error);
  w.Field("mean_error", l.mean_error);
  w.Field("share_above_epsilon", l.share_above_epsilon);
  w.EndObject();
}

void WriteMethod(JsonWriter& w, const MethodRow& m) {
  w.BeginObject();
  w.Field("method", m.method);
  w.Field("epsilon", m.epsilon);
  w.Field("ran", m.not_run.empty());
  if (!m.not_run.empty()) {
    w.Field("not_run", m.not_run);
    w.EndObject();
    return;
  }
  w.Field("tets", m.tets);
  w.Field("rounds", m.rounds);
  w.Field("midpoint_max_error", m.midpoint_max);
  w.Field("midpoint_mean_error", m.midpoint_mean);
  WriteLattice(w, m.lattice);
  WriteQuality(w, "quality", m.quality);
  w.Field("stop_reason", m.stop_reason);
  w.Field("seconds", m.seconds);
  if (m.method != kUniformMethod) WriteMatch(w, "uniform_at_lattice_max", m.uniform_at_max);
  if (m.has_self_report) {
    const PeerSelfReport& r = m.self_report;
    w.Key("self_report");
    w.BeginObject();
    w.Field("version", r.version);
    w.Field("rounds", r.rounds);
    w.Field("stop_reason", r.stop_reason);
    w.Field("seconds", r.seconds);
    w.Field("setup_seconds", r.setup_seconds);
    w.Field("tets", r.tets);
    w.Field("midpoint_max_error", r.midpoint_max);
    w.Field("lattice_max_error", r.lattice_max);
    w.Field("lattice_mean_error", r.lattice_mean);
    w.Field("quality_min", r.quality_min);
    w.Field("quality_mean", r.quality_mean);
    w.EndObject();
  }
  w.EndObject();
}

void WriteRun(JsonWriter& w, const RunRecord& r) {
  w.BeginObject();
  w.Field("scheme", r.scheme);
  w.Field("epsilon", r.epsilon);
  w.Field("max_iterations", r.max_iterations);
  w.Field("stop_reason", r.stop_reason);
  w.Field("initial_tets", r.initial_tets);
  w.Field("final_tets", r.final_tets);
  WriteQuality(w, "initial_quality", r.initial_quality);
  WriteQuality(w, "final_quality", r.final_quality);
  w.Field("final_max_error", r.final_max_error);
  w.Field("final_mean_error", r.final_mean_error);
  w.Field("certified_max_error", r.certified_max_error);
  WriteLattice(w, r.lattice);
  w.Field("seconds", r.seconds);
  w.Field("peak_added_bytes", r.peak_added_bytes);
  WriteMatch(w, "uniform_at_lattice_max", r.uniform_at_max);
  WriteMatch(w, "uniform_at_lattice_mean", r.uniform_at_mean);
  w.Key("iterations");
  w.BeginArray();
  for (const IterationStats& s : r.iterations) WriteIteration(w, s);
  w.EndArray();
  w.EndObject();
}

void WriteCase(JsonWriter& w, const CaseRecord& c) {
  w.BeginObject();
  w.Field("name", c.name);
  w.Field("volume", c.volume_name);
  w.Field("mesh_kind", c.mesh_kind);
  w.Field("description", c.description);
  w.Key("dims");
  w.BeginArray();
  for (int64_t d : c.dims) w.Int(d);
  w.EndArray();
  w.Key("spacing");
  w.BeginArray();
  for (double s : c.spacing) w.Number(s);
  w.EndArray();
  w.Field("voxel_type", c.voxel_type);
  w.Field("norm_coeff", c.norm_coeff);
  w.Field("input_vertices", c.input_vertices);
  w.Field("input_tets", c.input_tets);
  w.Key("runs");
  w.BeginArray();
  for (const RunRecord& r : c.runs) WriteRun(w, r);
  w.EndArray();
  w.Field("uniform_cap_tets", c.uniform_cap_tets);
  w.Key("uniform_levels");
  w.BeginArray();
  for (const BaselineLevel& l : c.uniform) {
    w.BeginObject();
    w.Field("level", l.level);
    w.Field("tets", l.tets);
    w.Field("lattice_max_error", l.lattice_max);
    w.Field("lattice_mean_error", l.lattice_mean);
    w.Field("midpoint_max_error", l.midpoint_max);
    w.Field("midpoint_mean_error", l.midpoint_mean);
    WriteQuality(w, "quality", l.quality);
    w.Field("seconds", l.seconds);
    w.EndObject();
  }
  w.EndArray();
  w.Key("methods");
  w.BeginArray();
  for (const MethodRow& m : c.methods) WriteMethod(w, m);
  w.EndArray();
  w.EndObject();
}

constexpr const char* kLocationNames[kNumMaxLocations] = {"vertex", "edge_midpoint", "edge_other",
                                                          "face", "interior"};

void WriteStudy(JsonWriter& w, const StudyRecord& s) {
  w.BeginObject();
  w.Field("mesh", s.mesh);
  w.Field("kind", s.kind);
  w.Field("tets", s.study.tets);
  w.Field("tets_sampled", s.study.tets_sampled);
  w.Field("class_mismatches", s.study.class_mismatches);
  w.Key("by_threshold");
  w.BeginArray();
  for (const LocationCounts& c : s.study.counts) {
    w.BeginObject();
    w.Field("threshold", c.threshold);
    w.Field("counted", c.counted);
    for (int l = 0; l < kNumMaxLocations; ++l) w.Field(kLocationNames[l], c.by_location[l]);
    w.Field("near_edge_midpoint", c.near_midpoint);
    w.EndObject();
  }
  w.EndArray();
  w.EndObject();
}

}  // namespace

std::string ResultsJson(const ReportData& d) {
  JsonWriter w;
  w.BeginObject();
  w.Field("schema", "tetrefine.reproduce/2");
  w.Field("generated_at", d.generated_at);
  w.Field("command", d.command);
  w.Field("quick", d.quick);
  w.Field("hardware_threads", d.hardware_threads);
  w.Key("epsilons");
  w.BeginArray();
  for (double e : d.epsilons) w.Number(e);
  w.EndArray();
  w.Field("max_iterations", d.max_iterations);
  w.Field("max_tets", d.max_tets);
  w.Field("uniform_cap_tets", d.uniform_cap_tets);
  w.Key("schemes");
  w.BeginArray();
  for (const std::string& scheme : d.schemes) w.String(scheme);
  w.EndArray();
  w.Field("plaza", d.plaza_status);
  w.Field("total_seconds", d.total_seconds);
  w.Key("notes");
  w.BeginArray();
  for (const std::string& n : d.notes) w.String(n);
  w.EndArray();
  w.Key("cases");
  w.BeginArray();
  for (const CaseRecord& c : d.cases) WriteCase(w, c);
  w.EndArray();
  w.Key("max_location_study");
  w.BeginObject();
  w.Field("lattice_n", 8);
  w.Field("max_tets_per_mesh", d.study_max_tets);
  w.Key("meshes");
  w.BeginArray();
  for (const StudyRecord& s : d.study) WriteStudy(w, s);
  w.EndArray();
  w.EndObject();
  w.EndObject();
  return w.Take();
}

}  // namespace tetrefine::reproduce
