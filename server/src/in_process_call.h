// One call of any gRPC method through a channel, by method path, with
// serialized messages in and out: how the REST face reaches the very service
// implementations (and status mapping) the gRPC face uses. Every gRPC call is
// a stream on the wire, so one class serves unary and streaming methods.
// Blocking; not thread-safe (one call, one thread at a time).
#pragma once

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace insdiag::server {

// Request metadata: the caller's credentials and address (access_guard.h).
using CallMetadata = std::vector<std::pair<std::string, std::string>>;

class InProcessCall {
 public:
  // `method` as on the wire: "/insdiag.v1.RunService/GetRun".
  InProcessCall(grpc::GenericStub& stub, const std::string& method, const CallMetadata& metadata);
  ~InProcessCall();
  InProcessCall(const InProcessCall&) = delete;
  InProcessCall& operator=(const InProcessCall&) = delete;

  // False once the server has closed the stream (Finish tells why).
  bool Write(const std::string& message);
  void WritesDone();
  // False at the end of the responses.
  bool Read(std::string* message);
  // The client no longer wants the responses (an HTTP client that went
  // away): the server's method sees the call cancelled, and a write it
  // waits on returns, so that Finish does not wait for it.
  void Cancel() { context_.TryCancel(); }
  grpc::Status Finish();

 private:
  bool Await();  // the completion of the one operation in flight

  grpc::ClientContext context_;
  grpc::CompletionQueue queue_;
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call_;
  bool started_ = false;
  bool writes_done_ = false;
  bool finished_ = false;
  grpc::Status status_;
};

}  // namespace insdiag::server
