#include "tests/hardening/raw_call.h"

#include <utility>

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
                          std::chrono::milliseconds timeout, const char* method,
                          std::vector<std::string>* responses) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  grpc::CompletionQueue queue;
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call =
      stub.PrepareCall(&context, method, &queue);
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
    if (responses == nullptr) continue;
    std::vector<grpc::Slice> slices;
    std::string bytes;
    if (response.Dump(&slices).ok()) {
      for (const grpc::Slice& slice : slices) {
        bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
      }
    }
    responses->push_back(std::move(bytes));
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
