#include "tests/hardening/raw_call.h"

#include "grpcpp/generic/generic_stub.h"

namespace tetrefine::hardening {
namespace {

// Waits for the completion of the operation tagged `tag`; false if it failed.
bool Await(grpc::CompletionQueue& queue, void* tag) {
  void* got = nullptr;
  bool ok = false;
  while (queue.Next(&got, &ok)) {
    if (got == tag) return ok;
  }
  return false;
}

}  // namespace

grpc::Status SendRawBytes(const std::shared_ptr<grpc::Channel>& channel,
                          const std::vector<std::string>& messages,
                          std::chrono::milliseconds timeout) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  grpc::CompletionQueue queue;
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call =
      stub.PrepareCall(&context, "/tetrefine.v1.Refiner/Refine", &queue);
  int tag = 0;
  call->StartCall(&tag);
  bool open = Await(queue, &tag);
  for (const std::string& bytes : messages) {
    if (!open) break;
    grpc::Slice slice(bytes);
    grpc::ByteBuffer buffer(&slice, 1);
    call->Write(buffer, &tag);
    open = Await(queue, &tag);
  }
  if (open) {
    call->WritesDone(&tag);
    Await(queue, &tag);
  }
  // Responses are drained until the server ends the stream.
  for (grpc::ByteBuffer response;;) {
    call->Read(&response, &tag);
    if (!Await(queue, &tag)) break;
  }
  grpc::Status status;
  call->Finish(&status, &tag);
  Await(queue, &tag);
  queue.Shutdown();
  void* ignored_tag;
  bool ignored_ok;
  while (queue.Next(&ignored_tag, &ignored_ok)) {
  }
  return status;
}

}  // namespace tetrefine::hardening
