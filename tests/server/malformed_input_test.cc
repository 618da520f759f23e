// Every malformed request of the one table (tests/support/malformed_requests.h), sent to an
// in-process server, gets its status code and a message naming the field and the index or value,
// and the server keeps serving good requests afterwards.

#include <random>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/support/loopback_server.h"
#include "tests/support/malformed_requests.h"

namespace tetrefine::testing {
namespace {

using Requests = RefineRequests;

class ServiceMalformedInputTest : public ::testing::TestWithParam<MalformedRequest> {
 protected:
  static void SetUpTestSuite() { server_ = new LoopbackServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  static LoopbackServer* server_;
};
LoopbackServer* ServiceMalformedInputTest::server_ = nullptr;

TEST_P(ServiceMalformedInputTest, IsRejectedNamingTheFieldAndTheServerCarriesOn) {
  const MalformedRequest& m = GetParam();
  const grpc::Status status = SendRaw(server_->NewChannel(), m.requests());
  EXPECT_EQ(status.error_code(), m.code) << status.error_message();
  for (const std::string& part : m.message_parts) {
    EXPECT_THAT(status.error_message(), ::testing::HasSubstr(part));
  }
  const grpc::Status good = SendRaw(server_->NewChannel(), GoodRequests());
  EXPECT_TRUE(good.ok()) << good.error_message();
}

INSTANTIATE_TEST_SUITE_P(All, ServiceMalformedInputTest, ::testing::ValuesIn(MalformedRequests()),
                         [](const ::testing::TestParamInfo<MalformedRequest>& info) {
                           return info.param.name;
                         });

// Random byte flips in random messages: whatever the server makes of them, it answers (never
// crashes) and then serves a good request.
TEST(ServiceFuzzedInputTest, ByteFlipsNeverBreakTheServer) {
  LoopbackServer server;
  std::mt19937_64 rng(20240601);
  const Requests valid = GoodRequests();
  int rejected = 0;
  for (int round = 0; round < 300; ++round) {
    Requests requests = valid;
    const size_t target = rng() % requests.size();
    std::string bytes = requests[target].SerializeAsString();
    if (bytes.empty()) continue;
    for (int flips = 1 + static_cast<int>(rng() % 3); flips > 0; --flips) {
      bytes[rng() % bytes.size()] = static_cast<char>(rng());
    }
    if (!requests[target].ParseFromString(bytes)) continue;
    const grpc::Status status = SendRaw(server.NewChannel(), requests);
    if (!status.ok()) {
      ++rejected;
      EXPECT_THAT(status.error_code(), ::testing::AnyOf(grpc::StatusCode::INVALID_ARGUMENT,
                                                        grpc::StatusCode::RESOURCE_EXHAUSTED))
          << status.error_message();
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_TRUE(SendRaw(server.NewChannel(), valid).ok());
}

}  // namespace
}  // namespace tetrefine::testing
