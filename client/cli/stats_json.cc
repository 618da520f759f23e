#include "client/cli/stats_json.h"

#include "client/io/json_writer.h"
#include "core/configuration.h"

namespace tetrefine::cli {

using io::JsonWriter;
namespace {

void WriteQuality(JsonWriter& json, const QualityStats& q) {
  json.BeginObject();
  json.Key("min");
  json.Number(q.min);
  json.Key("mean");
  json.Number(q.mean);
  json.Key("count");
  json.Int(q.count);
  json.EndObject();
}

void WriteIteration(JsonWriter& json, const IterationStats& s) {
  json.BeginObject();
  json.Key("iteration");
  json.Int(s.iteration);
  json.Key("initial_tets");
  json.Int(s.initial_tets);
  json.Key("final_tets");
  json.Int(s.final_tets);
  json.Key("tets_with_error");
  json.Int(s.tets_with_error);
  json.Key("edges");
  json.Int(s.edges);
  json.Key("split_edges");
  json.Int(s.split_edges);
  json.Key("short_edges_kept");
  json.Int(s.short_edges_kept);
  json.Key("max_error");
  json.Number(s.max_error);
  json.Key("mean_error");
  json.Number(s.mean_error);
  json.Key("configurations");
  json.BeginObject();
  for (int c = 0; c < kNumConfigurations; ++c) {
    json.Key(ConfigurationName(static_cast<Configuration>(c)));
    json.Int(s.configurations[c]);
  }
  json.EndObject();
  json.Key("schonhardt_prisms");
  json.Int(s.schonhardt_prisms);
  json.Key("max_segment_error");
  json.Number(s.max_segment_error);
  json.Key("closure_edges");
  json.Int(s.closure_edges);
  json.Key("guard_edges");
  json.Int(s.guard_edges);
  json.Key("other_tilings");
  json.Int(s.other_tilings);
  json.Key("failing_tets");
  json.Int(s.failing_tets);
  json.Key("quality");
  WriteQuality(json, s.quality);
  json.Key("seconds");
  json.Number(s.seconds);
  json.EndObject();
}

void WriteOptions(JsonWriter& json, const RunDescription& run) {
  const client::RefineRequestOptions& o = run.options;
  json.BeginObject();
  json.Key("epsilon");
  json.Number(o.refine.epsilon);
  json.Key("max_iterations");
  json.Int(o.refine.max_iterations);
  json.Key("max_tets");
  if (o.send_max_tets) {
    json.Int(o.refine.max_tets);
  } else {
    json.Null();
  }
  json.Key("norm_coeff");
  if (o.refine.norm_coeff.has_value()) {
    json.Number(*o.refine.norm_coeff);
  } else {
    json.Null();
  }
  json.Key("quality_reference");
  if (o.refine.quality_reference.has_value()) {
    json.Number(*o.refine.quality_reference);
  } else {
    json.Null();
  }
  json.Key("scheme");
  json.String(RefineSchemeName(o.refine.scheme));
  json.Key("certify");
  json.Bool(o.refine.certify);
  json.Key("lattice_n");
  json.Int(o.refine.lattice_n);
  // These four change the result too: three runs of 100,440, 55,735 and 8,162 tets wrote the
  // same options (an outside review, 2026-11-29), so a file could not repeat its run.
  json.Key("lattice_max_tets");
  json.Int(o.refine.lattice_max_tets);
  json.Key("lattice_seed");
  json.Int(static_cast<int64_t>(o.refine.lattice_seed));
  json.Key("min_edge_length");  // null: the core's default (see refine --help)
  if (o.refine.min_edge_length.has_value()) {
    json.Number(*o.refine.min_edge_length);
  } else {
    json.Null();
  }
  json.Key("min_quality");
  if (o.refine.min_quality.has_value()) {
    json.Number(*o.refine.min_quality);
  } else {
    json.Null();
  }
  json.Key("clamp");
  json.Bool(o.refine.outside == OutsidePolicy::kClamp);
  json.Key("fix_orientation");
  json.Bool(o.refine.orientation == OrientationPolicy::kNormalize);
  json.Key("fit_mesh_to_volume");
  json.Bool(run.fit_mesh_to_volume);
  json.EndObject();
}

}  // namespace

std::string RefineStatsJson(const RunDescription& run, const client::ClientResult& reply) {
  const RefineResult& r = reply.result;
  JsonWriter json;
  json.BeginObject();
  json.Key("volume");
  json.String(run.volume_path);
  json.Key("mesh");
  json.String(run.mesh_path);
  json.Key("output");
  json.String(run.output_path);
  json.Key("backend");
  json.String(run.backend);
  json.Key("options");
  WriteOptions(json, run);
  json.Key("input");
  json.BeginObject();
  json.Key("vertices");
  json.Int(run.input_vertices);
  json.Key("tets");
  json.Int(run.input_tets);
  json.EndObject();
  json.Key("norm_coeff");
  json.Number(r.norm_coeff);
  json.Key("iterations");
  json.BeginArray();
  for (const IterationStats& s : r.iterations) WriteIteration(json, s);
  json.EndArray();
  json.Key("stop_reason");
  json.String(StopReasonName(r.stop_reason));
  json.Key("next_iteration_tets");
  json.Int(r.next_iteration_tets);
  json.Key("next_iteration_min_quality");
  json.Number(r.next_iteration_min_quality);
  json.Key("quality");
  json.BeginObject();
  json.Key("initial");
  WriteQuality(json, r.initial_quality);
  json.Key("final");
  WriteQuality(json, r.final_quality);
  json.EndObject();
  json.Key("lattice");
  json.BeginObject();
  json.Key("n");  // 0 when nothing was sampled (--lattice-n 0)
  json.Int(r.lattice.tets_sampled > 0 ? r.lattice.n : 0);
  json.Key("tets_sampled");
  json.Int(r.lattice.tets_sampled);
  json.Key("points_sampled");
  json.Int(r.lattice.points_sampled);
  json.Key("max_error");
  json.Number(r.lattice.max_error);
  json.Key("mean_error");
  json.Number(r.lattice.mean_error);
  json.Key("share_above_epsilon");
  json.Number(r.lattice.share_above_epsilon);
  // Each tet's points weighed by its volume: what the field's error over the region is, where
  // the per-point figures weigh the many small tets refinement packs where the error is.
  json.Key("volume_mean_error");
  json.Number(r.lattice.volume_mean_error);
  json.Key("volume_share_above_epsilon");
  json.Number(r.lattice.volume_share_above_epsilon);
  json.EndObject();
  json.Key("certified_max_error");  // null unless certify converged
  if (r.certified_max_error >= 0.0) {
    json.Number(r.certified_max_error);
  } else {
    json.Null();
  }
  json.Key("final_max_error");
  json.Number(r.final_max_error);
  json.Key("final_mean_error");
  json.Number(r.final_mean_error);
  json.Key("tets_reoriented");
  json.Int(r.tets_reoriented);
  json.Key("output_mesh");
  json.BeginObject();
  json.Key("vertices");
  json.Int(run.output_pieces > 0 ? run.piece_vertices : static_cast<int64_t>(r.mesh.points.size()));
  json.Key("tets");
  json.Int(run.output_pieces > 0 ? r.final_quality.count
                                 : static_cast<int64_t>(r.mesh.tets.size()));
  if (run.output_pieces > 0) {
    json.Key("pieces");
    json.Int(run.output_pieces);
  }
  json.EndObject();
  json.Key("seconds");
  json.BeginObject();
  json.Key("refine");
  json.Number(r.seconds);
  json.Key("service_input");
  json.Number(reply.service.input_seconds);
  json.Key("service_total");
  json.Number(reply.service.total_seconds);
  json.EndObject();
  json.Key("service_max_tets");
  json.Int(reply.service.max_tets);
  json.EndObject();
  return json.Take();
}

}  // namespace tetrefine::cli
