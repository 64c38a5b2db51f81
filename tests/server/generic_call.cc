#include "generic_call.h"

#include <future>

namespace insdiag::testing {
namespace {

class Call final : public grpc::ClientBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
 public:
  explicit Call(const std::vector<std::string>& requests) {
    for (const std::string& bytes : requests) {
      grpc::Slice slice(bytes);
      requests_.emplace_back(&slice, 1);
    }
  }
  void Begin(grpc::GenericStub& stub, grpc::ClientContext& context, const std::string& path) {
    stub.PrepareBidiStreamingCall(&context, path, grpc::StubOptions(), this);
    WriteNextOrClose();
    StartRead(&response_);
    StartCall();
  }
  void OnWriteDone(bool ok) override {
    if (ok) {
      WriteNextOrClose();
    } else {
      StartWritesDone();  // the server ended the call: nothing more goes
    }
  }
  void OnReadDone(bool ok) override {
    if (!ok) return;
    std::string bytes;
    std::vector<grpc::Slice> slices;
    if (response_.Dump(&slices).ok()) {
      for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
    }
    answer_.responses.push_back(std::move(bytes));
    StartRead(&response_);
  }
  void OnDone(const grpc::Status& status) override {
    answer_.status = status;
    done_.set_value(std::move(answer_));
  }
  std::future<GenericAnswer> Result() { return done_.get_future(); }

 private:
  void WriteNextOrClose() {
    if (next_ < requests_.size()) {
      StartWrite(&requests_[next_++]);
    } else {
      StartWritesDone();
    }
  }
  std::vector<grpc::ByteBuffer> requests_;
  std::size_t next_ = 0;
  grpc::ByteBuffer response_;
  GenericAnswer answer_;
  std::promise<GenericAnswer> done_;
};

}  // namespace

GenericAnswer CallGeneric(grpc::GenericStub& stub, const std::string& path,
                          const std::vector<std::string>& requests, std::chrono::seconds deadline) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + deadline);
  Call call(requests);
  auto result = call.Result();
  call.Begin(stub, context, path);
  return result.get();
}

}  // namespace insdiag::testing
