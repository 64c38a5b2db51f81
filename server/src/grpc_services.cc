#include "insdiag/server/grpc_services.h"

#include "insdiag/server/status_mapping.h"

namespace insdiag::server {
namespace {

template <typename Response>
grpc::Status Respond(absl::StatusOr<Response> result, Response* response) {
  if (!result.ok()) return ToGrpcStatus(result.status());
  *response = std::move(*result);
  return grpc::Status::OK;
}

}  // namespace

grpc::Status RunServiceGrpc::UploadRun(grpc::ServerContext* context,
                                       grpc::ServerReader<v1::UploadRunRequest>* reader, v1::Run* response) {
  auto upload = runs_.StartUpload();
  v1::UploadRunRequest message;
  while (reader->Read(&message)) {
    if (auto status = upload.Accept(message); !status.ok()) return ToGrpcStatus(status);
  }
  // Read() also ends when the client cancels or the connection drops: such
  // a stream is not finished and must store nothing.
  if (context->IsCancelled()) {
    return grpc::Status(grpc::StatusCode::CANCELLED, "the upload was cancelled; nothing was stored");
  }
  return Respond(upload.Finish(), response);
}

grpc::Status RunServiceGrpc::GetRun(grpc::ServerContext*, const v1::GetRunRequest* request, v1::Run* response) {
  return Respond(runs_.GetRun(*request), response);
}

grpc::Status RunServiceGrpc::ListRuns(grpc::ServerContext*, const v1::ListRunsRequest* request,
                                      v1::ListRunsResponse* response) {
  return Respond(runs_.ListRuns(*request), response);
}

grpc::Status RunServiceGrpc::DeleteRun(grpc::ServerContext*, const v1::DeleteRunRequest* request,
                                       google::protobuf::Empty*) {
  return ToGrpcStatus(runs_.DeleteRun(*request));
}

grpc::Status RunServiceGrpc::ReadRunSamples(grpc::ServerContext* context, const v1::ReadRunSamplesRequest* request,
                                            grpc::ServerWriter<v1::SampleChunk>* writer) {
  const absl::Status status =
      runs_.ReadRunSamples(*request, [&](const v1::SampleChunk& chunk) { return writer->Write(chunk); });
  if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  return ToGrpcStatus(status);
}

}  // namespace insdiag::server
