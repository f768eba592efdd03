#include "clients/tools/estimate/estimate_command.h"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "clients/tools/estimate/estimate_report.h"
#include "clients/tools/estimate/pose_csv.h"
#include "clients/tools/estimate/shape_plot.h"
#include "libs/core/error.h"
#include "libs/mechanics/manipulator_options.h"

namespace shapesense {
namespace {

// Fewer poses than this cannot give a stiffness and its spread.
constexpr int kMinPoses = 3;

std::string ReadTextFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": cannot open for reading");
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!file.good()) throw InputError(path + ": cannot write");
}

std::string PlotPath(const EstimateArgs& args) {
  if (!args.plot_path.empty() || args.out_path.empty()) return args.plot_path;
  return std::filesystem::path(args.out_path).replace_extension(".png").string();
}

void CheckOutputDirectory(const std::string& path) {
  if (path.empty()) return;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    throw InputError(path + ": cannot write: no directory " + parent.string());
  }
}

MethodResult Evaluate(const TendonModel& model, const std::vector<PoseSample>& poses,
                      StiffnessEstimate estimate) {
  MethodResult result{std::move(estimate), {}};
  if (result.estimate.valid) {
    result.tip_errors = ComputeTipErrors(model.WithStiffness(result.estimate.stiffness), poses);
  }
  return result;
}

EstimateReport Estimate(const TendonModel& model, const std::vector<PoseSample>& poses,
                        const EstimateArgs& args) {
  EstimationOptions options;
  options.max_relative_std = args.max_relative_std;
  EstimateReport report;
  report.model_source = args.model_path;
  report.data_source = args.data_path;
  report.num_poses = static_cast<int>(poses.size());
  report.distal_length = model.lengths().distal;
  report.nominal = model.stiffness();
  report.nominal_tip_errors = ComputeTipErrors(model, poses);
  report.methods.push_back(
      Evaluate(model, poses, EstimateStiffnessTensionless(model, poses, options)));
  report.methods.push_back(
      Evaluate(model, poses, EstimateStiffnessOutputError(model, poses, options)));
  report.primary = 1;
  if (args.use_tensions) {
    report.methods.push_back(
        Evaluate(model, poses, EstimateStiffnessFromTensions(model, poses, options)));
    report.primary = 2;
  }
  return report;
}

std::string EncodePng(const cv::Mat& image, const std::string& path) {
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", image, bytes)) throw InputError(path + ": cannot encode the plot");
  return std::string(bytes.begin(), bytes.end());
}

// Both outputs are made in memory first; a second that cannot be written
// takes the first away again, so a failure leaves nothing behind.
void WriteOutputs(const EstimateArgs& args, const EstimateReport& report, const TendonModel& model,
                  const std::vector<PoseSample>& poses, std::ostream& log) {
  const std::string plot_path = PlotPath(args);
  const MethodResult& primary = report.methods[report.primary];
  std::vector<std::pair<std::string, std::string>> outputs;
  if (!args.out_path.empty())
    outputs.emplace_back(args.out_path, ReportToJson(report).dump(2) + "\n");
  if (!plot_path.empty()) {
    const cv::Mat plot =
        PlotSensedAgainstModel(model.WithStiffness(primary.estimate.stiffness), poses,
                               {560, "model (" + primary.estimate.method + ")"});
    outputs.emplace_back(plot_path, EncodePng(plot, plot_path));
  }
  for (size_t i = 0; i < outputs.size(); ++i) {
    try {
      WriteFile(outputs[i].first, outputs[i].second);
    } catch (const InputError&) {
      for (size_t k = 0; k < i; ++k) std::filesystem::remove(outputs[k].first);
      throw;
    }
    log << "wrote " << outputs[i].first << "\n";
  }
}

int RunEstimateImpl(const EstimateArgs& args, std::ostream& log) {
  if (!(args.max_relative_std > 0.0)) {
    throw InputError("--max-relative-std: expected a positive number");
  }
  const TendonModel model(ParseManipulatorYaml(ReadTextFile(args.model_path), args.model_path));
  const std::vector<PoseSample> poses = ParsePoseCsv(ReadTextFile(args.data_path), args.data_path,
                                                     model.num_tendons(), args.use_tensions);
  if (static_cast<int>(poses.size()) < kMinPoses) {
    throw InputError(args.data_path + ": expected at least " + std::to_string(kMinPoses) +
                     " poses, got " + std::to_string(poses.size()));
  }
  CheckOutputDirectory(args.out_path);
  CheckOutputDirectory(PlotPath(args));
  const EstimateReport report = Estimate(model, poses, args);
  PrintReport(report, log);
  const StiffnessEstimate& primary = report.methods[report.primary].estimate;
  if (!primary.valid) {
    log << "error: the " << primary.method << " estimate failed: " << primary.message << "\n";
    return 2;
  }
  WriteOutputs(args, report, model, poses, log);
  return 0;
}

}  // namespace

int RunEstimate(const EstimateArgs& args, std::ostream& log) {
  try {
    return RunEstimateImpl(args, log);
  } catch (const InputError& e) {
    log << "error: " << e.what() << "\n";
    return 1;
  }
}

void AddEstimateCommand(CLI::App& app) {
  auto args = std::make_shared<EstimateArgs>();
  CLI::App* command =
      app.add_subcommand("estimate", "Estimate the manipulator's stiffnesses from sensed poses");
  command
      ->add_option("--model", args->model_path, "manipulator model YAML (config/manipulator.yaml)")
      ->required();
  command
      ->add_option("--data", args->data_path,
                   "pose CSV: y0..y(n-1), kappa_x, kappa_z, eps0, eps1 [, tau0..tau(n-1)]")
      ->required();
  command->add_flag(
      "--tensions", args->use_tensions,
      "use the measured tensions tau0.. (the estimate written is the tension-based one)");
  command->add_option("--out", args->out_path, "write the result as JSON here");
  command->add_option("--plot", args->plot_path,
                      "write the sensed-against-model plot (PNG) here (default: --out with .png)");
  command
      ->add_option("--max-relative-std", args->max_relative_std,
                   "warn when a stiffness's standard deviation exceeds this fraction of it")
      ->capture_default_str();
  command->callback([args] {
    if (const int code = RunEstimate(*args, std::cout); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace shapesense
