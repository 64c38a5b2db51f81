// insdiag import LOG (-o RUN.csv | --upload) [--preset NAME] [--settings FILE]
//                    [--columns ...] [--units ...] [--axes ...] [--rate-hz HZ]
//                    [--binary TYPE] [--attitude constant|level|columns]
//                    [--ref-rpy-deg R,P,Y] [--heading-deg H] [--level-window-s S]
//                    [--serial S] [--unit-type T] [--site LAT,LON,HEIGHT]
//                    [--set KEY=VALUE ...]
// Turns a raw IMU log into a bench run (docs/IMPORT.md): writes it, or
// uploads it and prints the run's name. The options override the side file,
// which overrides the preset.
#include <ostream>

#include "insdiag/benchrun/bench_run_csv.h"
#include "insdiag/client/run_client.h"
#include "insdiag/importers/bench_run_import.h"
#include "insdiag/importers/presets.h"
#include "server_output.h"
#include "verb.h"

namespace insdiag::cli {
namespace {

class ImportVerb final : public Verb {
 public:
  std::string Name() const override { return "import"; }
  std::string Summary() const override {
    return "Turn a raw IMU log (text, binary, vendor presets) into a bench run; write or upload it";
  }

  void DeclareOptions(OptionSink& options) override {
    options.Positional("LOG", &log_, "The raw log");
    options.Option("-o,--output", &output_, "Write the bench run here (RUN.csv)");
    options.Flag("--upload", &upload_, "Upload the bench run to the server and print the run's name");
    std::string presets;
    for (const std::string& name : importers::PresetNames()) presets += (presets.empty() ? "" : ", ") + name;
    options.Option("--preset", &preset_, "A vendor layout: " + presets);
    options.Option("--settings", &settings_file_,
                   "A side file of settings: flat YAML `key: value` lines or a flat JSON object (docs/IMPORT.md)");
    for (const FlagSetting& f : kFlagSettings) options.Option(f.flag, &flag_values_[&f - kFlagSettings], f.help);
    options.Option("--site", &site_, "Site latitude and longitude [deg] and ellipsoidal height [m]: LAT,LON,HEIGHT");
    options.Option("--ref-rpy-deg", &ref_rpy_, "A constant reference attitude [deg]: ROLL,PITCH,YAW");
    options.Option("--binary", &binary_type_, "The log is binary records of this little-endian type: f32, f64, i16, i32");
    options.Repeated("--set", &sets_, "Any setting, KEY=VALUE (docs/IMPORT.md), e.g. --set meta.bench=T-3");
    server_.Declare(options);
    options.Option("--request-id", &request_id_, "Idempotency key of the upload (default: a new random key)");
  }

  int Run(std::ostream& out, std::ostream& err) override {
    if (output_.empty() == !upload_) return Usage(err, "give exactly one of --output RUN.csv and --upload");
    importers::ImportSettings settings;
    if (!settings_file_.empty()) {
      // A side file refused names its line and key: a refused input, not usage.
      auto file = importers::ReadSettingsFile(settings_file_);
      if (!file.ok()) {
        err << file.status().message() << "\n";
        return kExitRefused;
      }
      settings = *std::move(file);
    }
    if (absl::Status added = AddOptionSettings(settings); !added.ok()) return Usage(err, std::string(added.message()));
    auto run = importers::ImportBenchRunFile(log_, settings);
    if (!run.ok()) {
      err << run.status().message() << "\n";
      return kExitRefused;
    }
    if (!output_.empty()) {
      if (absl::Status written = benchrun::WriteBenchRunFile(*run, output_); !written.ok()) {
        err << written.message() << "\n";
        return kExitRefused;
      }
      out << output_ << ": " << run->samples.size() << " samples, " << run->DurationS() << " s\n";
      return kExitOk;
    }
    auto stub = v1::RunService::NewStub(server_.Connect());
    client::UploadOptions options;
    options.request_id = request_id_.empty() ? client::NewRequestId() : request_id_;
    auto stored = client::UploadRun(*stub, *run, options);
    if (!stored.ok()) return RequestFailed(err, "import", server_.address, stored.status());
    out << stored->name() << "\n";
    return kExitOk;
  }

 private:
  // An option that sets one setting, as `--set KEY=VALUE` would.
  struct FlagSetting {
    const char* flag;
    const char* key;
    const char* help;
  };
  static constexpr FlagSetting kFlagSettings[] = {
      {"--columns", "columns", "What each field holds, in order: t, gyro_x..z, acc_x..z, ref_roll, ref_pitch, "
                               "ref_yaw, table_yaw, temp, gps_week or - (skip); '-name' for a negated field"},
      {"--units", "units", "Units by group or column, e.g. gyro=deg/s,acc=g,t=ms or gyro=0.1*arcsec (counts)"},
      {"--axes", "axes", "Body axes from the log's axes, e.g. x=-y,y=x,z=-z"},
      {"--rate-hz", "rate_hz", "Sample rate, when no column holds t"},
      {"--attitude", "attitude", "Reference attitude: constant, level (default) or columns"},
      {"--heading-deg", "heading_deg", "Levelled attitude: this heading instead of gyro-compassing"},
      {"--level-window-s", "level_window_s", "Levelled attitude: the static start to level over (default: all)"},
      {"--serial", "unit_serial", "The unit's serial number"},
      {"--unit-type", "unit_type", "The unit's type, e.g. INS-2000"},
  };

  // The options' settings, over the side file's.
  absl::Status AddOptionSettings(importers::ImportSettings& settings) const {
    const auto set = [&](std::string key, std::string value, const std::string& flag) {
      settings.Set(std::move(key), std::move(value), {"command line", 0, 0, flag});
    };
    if (!preset_.empty()) set("preset", preset_, "--preset");
    for (std::size_t i = 0; i < std::size(kFlagSettings); ++i) {
      if (!flag_values_[i].empty()) set(kFlagSettings[i].key, flag_values_[i], kFlagSettings[i].flag);
    }
    if (!binary_type_.empty()) {
      set("log_format", "binary", "--binary");
      set("binary_type", binary_type_, "--binary");
    }
    if (!site_.empty()) {
      const std::vector<std::string> parts = SplitList(site_);
      if (parts.size() != 3) return absl::InvalidArgumentError("--site: give LAT,LON,HEIGHT");
      set("site_latitude_deg", parts[0], "--site");
      set("site_longitude_deg", parts[1], "--site");
      set("site_height_m", parts[2], "--site");
    }
    if (!ref_rpy_.empty()) {
      const std::vector<std::string> parts = SplitList(ref_rpy_);
      if (parts.size() != 3) return absl::InvalidArgumentError("--ref-rpy-deg: give ROLL,PITCH,YAW");
      set("attitude", "constant", "--ref-rpy-deg");
      set("ref_roll_deg", parts[0], "--ref-rpy-deg");
      set("ref_pitch_deg", parts[1], "--ref-rpy-deg");
      set("ref_yaw_deg", parts[2], "--ref-rpy-deg");
    }
    for (const std::string& kv : sets_) {
      const std::size_t eq = kv.find('=');
      if (eq == std::string::npos) return absl::InvalidArgumentError("--set: '" + kv + "' is not KEY=VALUE");
      set(kv.substr(0, eq), kv.substr(eq + 1), "--set " + kv.substr(0, eq));
    }
    return absl::OkStatus();
  }

  static std::vector<std::string> SplitList(const std::string& text) {
    std::vector<std::string> parts(1);
    for (char c : text) {
      if (c == ',') parts.emplace_back();
      else parts.back() += c;
    }
    return parts;
  }

  int Usage(std::ostream& err, const std::string& why) const {
    err << "insdiag import: " << why << "\n";
    return kExitUsage;
  }

  std::string log_, output_, preset_, settings_file_, site_, ref_rpy_, binary_type_, request_id_;
  bool upload_ = false;
  std::string flag_values_[std::size(kFlagSettings)];
  std::vector<std::string> sets_;
  ServerFlags server_;
};

}  // namespace

std::unique_ptr<Verb> MakeVerb_import() { return std::make_unique<ImportVerb>(); }

}  // namespace insdiag::cli
