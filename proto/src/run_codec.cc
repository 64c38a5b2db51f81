#include "insdiag/api/run_codec.h"

#include <absl/strings/escaping.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <numbers>

namespace insdiag::api {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

// The optional datasheet fields, listed once for both directions.
struct DatasheetField {
  std::optional<double> engine::Datasheet::*value;
  bool (v1::Datasheet::*has)() const;
  double (v1::Datasheet::*get)() const;
  void (v1::Datasheet::*set)(double);
};
constexpr std::array kDatasheetFields = {
    DatasheetField{&engine::Datasheet::gyro_arw_rad_rts, &v1::Datasheet::has_gyro_arw_rad_rts,
                   &v1::Datasheet::gyro_arw_rad_rts, &v1::Datasheet::set_gyro_arw_rad_rts},
    DatasheetField{&engine::Datasheet::gyro_bias_sigma_rad_s, &v1::Datasheet::has_gyro_bias_sigma_rad_s,
                   &v1::Datasheet::gyro_bias_sigma_rad_s, &v1::Datasheet::set_gyro_bias_sigma_rad_s},
    DatasheetField{&engine::Datasheet::gyro_bias_tau_s, &v1::Datasheet::has_gyro_bias_tau_s,
                   &v1::Datasheet::gyro_bias_tau_s, &v1::Datasheet::set_gyro_bias_tau_s},
    DatasheetField{&engine::Datasheet::acc_vrw_mps_rts, &v1::Datasheet::has_acc_vrw_mps_rts,
                   &v1::Datasheet::acc_vrw_mps_rts, &v1::Datasheet::set_acc_vrw_mps_rts},
    DatasheetField{&engine::Datasheet::acc_bias_sigma_mps2, &v1::Datasheet::has_acc_bias_sigma_mps2,
                   &v1::Datasheet::acc_bias_sigma_mps2, &v1::Datasheet::set_acc_bias_sigma_mps2},
    DatasheetField{&engine::Datasheet::acc_bias_tau_s, &v1::Datasheet::has_acc_bias_tau_s,
                   &v1::Datasheet::acc_bias_tau_s, &v1::Datasheet::set_acc_bias_tau_s},
};

void AppendLittleEndian(double value, std::array<unsigned char, 88>& buffer, std::size_t& used) {
  auto bits = std::bit_cast<std::uint64_t>(value);
  for (int byte = 0; byte < 8; ++byte) {
    buffer[used++] = static_cast<unsigned char>(bits & 0xffU);
    bits >>= 8;
  }
}

}  // namespace

v1::RunMetadata ToProto(const engine::BenchRunMetadata& metadata, bool has_temperature) {
  v1::RunMetadata out;
  out.set_format(metadata.format);
  out.set_unit_serial(metadata.unit_serial);
  out.set_unit_type(metadata.unit_type);
  out.mutable_site()->set_latitude_deg(metadata.site.latitude_rad / kRadPerDeg);
  out.mutable_site()->set_longitude_deg(metadata.site.longitude_rad / kRadPerDeg);
  out.mutable_site()->set_height_m(metadata.site.height_m);
  for (const auto& field : kDatasheetFields) {
    if (const auto& value = metadata.datasheet.*field.value) (out.mutable_datasheet()->*field.set)(*value);
  }
  for (const auto& [key, value] : metadata.extra) {
    auto* entry = out.add_extra();
    entry->set_key(key);
    entry->set_value(value);
  }
  out.set_has_temperature(has_temperature);
  for (const std::size_t start : metadata.segment_starts) out.add_segment_starts(start);
  return out;
}

engine::BenchRunMetadata FromProto(const v1::RunMetadata& metadata) {
  engine::BenchRunMetadata out;
  out.format = metadata.format();
  out.unit_serial = metadata.unit_serial();
  out.unit_type = metadata.unit_type();
  out.site.latitude_rad = metadata.site().latitude_deg() * kRadPerDeg;
  out.site.longitude_rad = metadata.site().longitude_deg() * kRadPerDeg;
  out.site.height_m = metadata.site().height_m();
  for (const auto& field : kDatasheetFields) {
    if ((metadata.datasheet().*field.has)()) out.datasheet.*field.value = (metadata.datasheet().*field.get)();
  }
  for (const auto& entry : metadata.extra()) out.extra.emplace_back(entry.key(), entry.value());
  out.segment_starts.assign(metadata.segment_starts().begin(), metadata.segment_starts().end());
  return out;
}

v1::Sample ToProto(const engine::ImuSample& sample) {
  v1::Sample out;
  out.set_t(sample.t_s);
  out.set_gyro_x(sample.gyro_rad_s.x());
  out.set_gyro_y(sample.gyro_rad_s.y());
  out.set_gyro_z(sample.gyro_rad_s.z());
  out.set_acc_x(sample.acc_mps2.x());
  out.set_acc_y(sample.acc_mps2.y());
  out.set_acc_z(sample.acc_mps2.z());
  out.set_ref_roll(sample.ref_rpy_rad.x());
  out.set_ref_pitch(sample.ref_rpy_rad.y());
  out.set_ref_yaw(sample.ref_rpy_rad.z());
  out.set_temp(sample.temp_degc);
  return out;
}

engine::ImuSample FromProto(const v1::Sample& sample) {
  return engine::ImuSample{
      .t_s = sample.t(),
      .gyro_rad_s = {sample.gyro_x(), sample.gyro_y(), sample.gyro_z()},
      .acc_mps2 = {sample.acc_x(), sample.acc_y(), sample.acc_z()},
      .ref_rpy_rad = {sample.ref_roll(), sample.ref_pitch(), sample.ref_yaw()},
      .temp_degc = sample.temp(),
  };
}

SampleDigest::SampleDigest(bool has_temperature)
    : has_temperature_(has_temperature), ctx_(EVP_MD_CTX_new()) {
  EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr);
}

void SampleDigest::Add(const engine::ImuSample& sample) {
  // Bytes are assembled explicitly so the digest is the same on any host
  // byte order.
  std::array<unsigned char, 88> buffer{};
  std::size_t used = 0;
  AppendLittleEndian(sample.t_s, buffer, used);
  for (const auto* vec : {&sample.gyro_rad_s, &sample.acc_mps2, &sample.ref_rpy_rad}) {
    for (int axis = 0; axis < 3; ++axis) AppendLittleEndian((*vec)[axis], buffer, used);
  }
  if (has_temperature_) AppendLittleEndian(sample.temp_degc, buffer, used);
  EVP_DigestUpdate(ctx_.get(), buffer.data(), used);
}

std::string SampleDigest::HexDigest() {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_DigestFinal_ex(ctx_.get(), digest.data(), &length);
  return absl::BytesToHexString(
      absl::string_view(reinterpret_cast<const char*>(digest.data()), length));
}

std::string SampleSha256(const engine::BenchRun& run) {
  SampleDigest digest(run.has_temperature);
  for (const auto& sample : run.samples) digest.Add(sample);
  return digest.HexDigest();
}

bool ForEachUploadRequest(const engine::BenchRun& run, const std::string& request_id,
                          std::size_t chunk_samples,
                          absl::FunctionRef<bool(const v1::UploadRunRequest&)> send) {
  chunk_samples = std::max<std::size_t>(chunk_samples, 1);
  v1::UploadRunRequest request;
  *request.mutable_metadata() = ToProto(run.metadata, run.has_temperature);
  request.mutable_metadata()->set_request_id(request_id);
  if (!send(request)) return false;

  SampleDigest digest(run.has_temperature);
  for (std::size_t begin = 0; begin < run.samples.size(); begin += chunk_samples) {
    const std::size_t end = std::min(run.samples.size(), begin + chunk_samples);
    auto* chunk = request.mutable_samples();
    chunk->mutable_samples()->Clear();
    chunk->mutable_samples()->Reserve(static_cast<int>(end - begin));
    for (std::size_t k = begin; k < end; ++k) {
      *chunk->add_samples() = ToProto(run.samples[k]);
      digest.Add(run.samples[k]);
    }
    if (!send(request)) return false;
  }
  request.set_sha256(digest.HexDigest());
  return send(request);
}

}  // namespace insdiag::api
