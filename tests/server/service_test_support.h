#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/mesh.h"
#include "core/refine.h"
#include "core/volume.h"
#include "grpcpp/grpcpp.h"
#include "server/refiner_service.h"
#include "tetrefine/v1/tetrefine.pb.h"

namespace tetrefine::testing {

// The test field: smooth, with enough curvature that refinement runs a few iterations.
double TestField(const Vec3& p);

// A whole volume of `dims` samples, spacing 1, origin 0, sampling TestField, stored as `type`
// (integer types round the field scaled by 100).
Volume TestVolume(const Index3& dims, VoxelType type = VoxelType::kFloat64);

// The slab [lo, hi) of TestVolume(dims, type).
Volume TestSlab(const Index3& dims, const Index3& lo, const Index3& hi,
                VoxelType type = VoxelType::kFloat64);

// The box [lo, hi] cut into `cells` cells per axis of 5 positively oriented tets each, with
// alternating cell parity so that shared faces match.
Mesh FiveTetMesh(const Vec3& lo, const Vec3& hi, const std::array<int, 3>& cells);

// A real tetrefine server on a loopback port.
class LoopbackServer {
 public:
  explicit LoopbackServer(const server::ServiceConfig& config = {});
  ~LoopbackServer();
  std::shared_ptr<grpc::Channel> NewChannel() const;
  server::RefinerService& service() { return *service_; }
  int port() const { return port_; }

 private:
  std::unique_ptr<server::RefinerService> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

// Sends `requests` as one Refine call, exactly as given, and returns the call's status.
grpc::Status SendRaw(const std::shared_ptr<grpc::Channel>& channel,
                     const std::vector<v1::RefineRequest>& requests);

// Bitwise comparisons (doubles compared as bit patterns).
void ExpectSameMesh(const Mesh& expected, const Mesh& actual);
void ExpectSameStats(const IterationStats& expected, const IterationStats& actual);
// Everything but wall times.
void ExpectSameResult(const RefineResult& expected, const RefineResult& actual);

}  // namespace tetrefine::testing
