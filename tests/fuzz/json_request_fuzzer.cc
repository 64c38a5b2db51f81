// JSON request decoding, as the REST face does it for every method: the
// first byte picks a method of an insdiag service, the rest is its request's
// JSON. Refused or accepted, never a crash; what is accepted prints back to
// JSON that decodes again.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/dynamic_message.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "insdiag/api/json.h"
#include "insdiag/v1/access.pb.h"
#include "insdiag/v1/analyses.pb.h"
#include "insdiag/v1/fleet.pb.h"
#include "insdiag/v1/knowledge.pb.h"
#include "insdiag/v1/live.pb.h"
#include "insdiag/v1/runs.pb.h"

namespace {

const std::vector<const google::protobuf::Descriptor*>& RequestTypes() {
  static const auto* types = [] {
    // Naming one message of each file links it in, which registers its services.
    for (const auto* file : {insdiag::v1::UploadRunRequest::descriptor()->file(),
                             insdiag::v1::CreateAnalysisRequest::descriptor()->file(),
                             insdiag::v1::GetUnitRequest::descriptor()->file(),
                             insdiag::v1::GetFleetStatisticsRequest::descriptor()->file(),
                             insdiag::v1::CreateTokenRequest::descriptor()->file(),
                             insdiag::v1::ListLiveRunsRequest::descriptor()->file()}) {
      if (file->service_count() == 0) std::abort();
    }
    auto* out = new std::vector<const google::protobuf::Descriptor*>();
    for (const char* name :
         {"insdiag.v1.RunService", "insdiag.v1.AnalysisService", "insdiag.v1.KnowledgeService",
          "insdiag.v1.FleetService", "insdiag.v1.AccessService", "insdiag.v1.LiveRunService"}) {
      const auto* service = google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(name);
      if (service == nullptr) std::abort();
      for (int m = 0; m < service->method_count(); ++m) out->push_back(service->method(m)->input_type());
    }
    return out;
  }();
  return *types;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto& types = RequestTypes();
  const auto* type = types[data[0] % types.size()];
  std::unique_ptr<google::protobuf::Message> message(
      google::protobuf::MessageFactory::generated_factory()->GetPrototype(type)->New());
  const std::string json(reinterpret_cast<const char*>(data + 1), size - 1);
  if (!insdiag::api::FromJson(json, message.get()).ok()) return 0;
  auto printed = insdiag::api::ToJson(*message);
  if (!printed.ok()) return 0;  // e.g. a string that is not UTF-8 cannot be printed
  std::unique_ptr<google::protobuf::Message> again(message->New());
  if (!insdiag::api::FromJson(*printed, again.get()).ok()) std::abort();
  return 0;
}
