#include "core/edge_statistics.h"

#include <functional>
#include <limits>

#include "core/edge_marking.h"
#include "core/edge_table.h"
#include "core/refine_state.h"

namespace tetrefine {

EdgeMidpointStats MeasureEdgeMidpoints(const Volume& volume, const Mesh& mesh, double norm,
                                       bool clamp) {
  refine_internal::State state;
  state.mesh.values = mesh.values;
  state.points = &mesh.points;
  state.tets = &mesh.tets;
  const EdgeTable edges = BuildEdgeTable(mesh.tets, static_cast<int64_t>(mesh.points.size()));
  refine_internal::EdgeTestParams params;
  params.norm = norm;
  params.epsilon = std::numeric_limits<double>::infinity();  // no edge is judged
  params.clamp = clamp;
  const std::function<bool()> no_poll;  // CancelFlag keeps a reference
  refine_internal::CancelFlag never(no_poll);
  const refine_internal::EdgeErrors errors =
      refine_internal::EvaluateEdges(volume, state, edges, params, nullptr, never);
  return {static_cast<int64_t>(edges.size()), errors.max_error, errors.mean_error};
}

}  // namespace tetrefine
