// The gRPC face: thin adapters from the generated service bases onto the
// transport-free services, with every error mapped by ToGrpcStatus.
#pragma once

#include "insdiag/server/run_service.h"
#include "insdiag/v1/runs.grpc.pb.h"

namespace insdiag::server {

class RunServiceGrpc final : public v1::RunService::Service {
 public:
  explicit RunServiceGrpc(RunService& runs) : runs_(runs) {}

  grpc::Status UploadRun(grpc::ServerContext* context, grpc::ServerReader<v1::UploadRunRequest>* reader,
                         v1::Run* response) override;
  grpc::Status GetRun(grpc::ServerContext* context, const v1::GetRunRequest* request,
                      v1::Run* response) override;
  grpc::Status ListRuns(grpc::ServerContext* context, const v1::ListRunsRequest* request,
                        v1::ListRunsResponse* response) override;
  grpc::Status DeleteRun(grpc::ServerContext* context, const v1::DeleteRunRequest* request,
                         google::protobuf::Empty* response) override;
  grpc::Status ReadRunSamples(grpc::ServerContext* context, const v1::ReadRunSamplesRequest* request,
                              grpc::ServerWriter<v1::SampleChunk>* writer) override;

 private:
  RunService& runs_;
};

}  // namespace insdiag::server
