// The REST gateway as a client reaches it: method, path, query, headers and
// body together, through RestGateway::Handle and the in-process gRPC call it
// makes. Behind the gateway stands a gRPC server with the health service and
// a stand-in for every other method (the gateway is what is fuzzed; the
// services' own parsing has its fuzzers): it answers either UNAUTHENTICATED,
// as the access guard does to a bad token, or OK with an empty message, so
// that the gateway's printing and streaming paths run too.
//
// Input: a first line "FLAGS METHOD PATH[?QUERY]" (FLAGS: 'o' for the OK
// stand-in), then header lines "Name: value" up to an empty line, then the
// body. Refused or answered, never a crash; gRPC aborts on metadata it
// refuses, so a header byte the edge lets through would show here.
#include <absl/strings/str_split.h>
#include <grpcpp/generic/async_generic_service.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "insdiag/server/insdiag_server.h"
#include "insdiag/server/rest_gateway.h"

// Last: httplib.h pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include <httplib.h>

namespace {

std::atomic<bool> answer_ok{false};

class StandIn final : public grpc::CallbackGenericService {
  grpc::ServerGenericBidiReactor* CreateReactor(grpc::GenericCallbackServerContext*) override {
    class Reactor final : public grpc::ServerGenericBidiReactor {
     public:
      // A refusal comes at once, as the access guard's; an answer after the
      // request is read, as a unary method's.
      Reactor() : ok_(answer_ok) {
        if (!ok_) {
          Finish(grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "stand-in: no token is valid here"));
          return;
        }
        StartRead(&request_);
      }
      void OnReadDone(bool read) override {
        if (read) return StartRead(&request_);
        grpc::Slice empty(std::string{});
        response_ = grpc::ByteBuffer(&empty, 1);
        StartWriteAndFinish(&response_, grpc::WriteOptions(), grpc::Status::OK);
      }
      void OnDone() override { delete this; }

     private:
      const bool ok_;
      grpc::ByteBuffer request_;
      grpc::ByteBuffer response_;
    };
    return new Reactor();
  }
};

struct Backend {
  Backend() {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::ServerBuilder builder;
    builder.RegisterCallbackGenericService(&stand_in);
    server = builder.BuildAndStart();
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(-1);
    gateway = *insdiag::server::RestGateway::Create(server->InProcessChannel(arguments),
                                                    insdiag::server::InsdiagServer::ServiceNames(), "fuzz-key");
  }
  StandIn stand_in;
  std::unique_ptr<grpc::Server> server;
  std::unique_ptr<insdiag::server::RestGateway> gateway;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Backend* backend = new Backend();  // for the process: gRPC's threads outlive any test case
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t head_end = input.find("\n\n");
  const std::string head = input.substr(0, head_end);
  httplib::Request request;
  request.body = head_end == std::string::npos ? "" : input.substr(head_end + 2);
  request.remote_addr = "127.0.0.1";
  request.remote_port = 40000;
  std::vector<std::string> lines = absl::StrSplit(head, '\n');
  std::vector<std::string> first = absl::StrSplit(lines[0], absl::MaxSplits(' ', 2));
  first.resize(3);
  answer_ok = first[0].find('o') != std::string::npos;
  request.method = first[1];
  const std::size_t question = first[2].find('?');
  request.path = first[2].substr(0, question);
  if (question != std::string::npos) {
    for (absl::string_view pair : absl::StrSplit(first[2].substr(question + 1), '&', absl::SkipEmpty())) {
      std::pair<std::string, std::string> kv = absl::StrSplit(pair, absl::MaxSplits('=', 1));
      request.params.emplace(kv.first, kv.second);
    }
  }
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::pair<std::string, std::string> header = absl::StrSplit(lines[i], absl::MaxSplits(": ", 1));
    request.headers.emplace(header.first, header.second);
  }
  httplib::Response response;
  backend->gateway->Handle(request, response);
  if (response.content_provider_) {  // a streamed answer: drain it as httplib would
    httplib::DataSink sink;
    std::string streamed;
    sink.write = [&](const char* bytes, std::size_t n) {
      streamed.append(bytes, n);
      return true;
    };
    sink.done = [] {};
    sink.is_writable = [] { return true; };
    response.content_provider_(0, 0, sink);
  }
  return 0;
}
