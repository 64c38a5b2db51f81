#include "in_process_call.h"

#include <vector>

namespace insdiag::server {

InProcessCall::InProcessCall(grpc::GenericStub& stub, const std::string& method, const CallMetadata& metadata) {
  // Metadata must be on the context before the call is prepared.
  for (const auto& [key, value] : metadata) context_.AddMetadata(key, value);
  call_ = stub.PrepareCall(&context_, method, &queue_);
  if (call_) {
    call_->StartCall(this);
    started_ = Await();
  }
}

InProcessCall::~InProcessCall() {
  if (started_ && !finished_) {
    context_.TryCancel();
    Finish();
  }
  queue_.Shutdown();
  void* tag = nullptr;
  bool ok = false;
  while (queue_.Next(&tag, &ok)) {
  }
}

bool InProcessCall::Await() {
  void* tag = nullptr;
  bool ok = false;
  return queue_.Next(&tag, &ok) && ok;
}

bool InProcessCall::Write(const std::string& message) {
  if (!started_ || writes_done_) return false;
  grpc::Slice slice(message);
  grpc::ByteBuffer buffer(&slice, 1);
  call_->Write(buffer, this);
  return Await();
}

void InProcessCall::WritesDone() {
  if (!started_ || writes_done_) return;
  writes_done_ = true;
  call_->WritesDone(this);
  Await();
}

bool InProcessCall::Read(std::string* message) {
  if (!started_) return false;
  grpc::ByteBuffer buffer;
  call_->Read(&buffer, this);
  if (!Await()) return false;
  std::vector<grpc::Slice> slices;
  buffer.Dump(&slices);
  message->clear();
  for (const auto& slice : slices) message->append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  return true;
}

grpc::Status InProcessCall::Finish() {
  if (!started_) return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the call could not be started");
  if (finished_) return status_;
  finished_ = true;
  call_->Finish(&status_, this);
  Await();
  return status_;
}

}  // namespace insdiag::server
