#include "clients/tools/estimate/estimate_report.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace shapesense {
namespace {

nlohmann::json FiniteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json StiffnessJson(const StiffnessVector& values) {
  nlohmann::json out = nlohmann::json::object();
  for (int j = 0; j < 4; ++j) {
    out[kStiffnessNames[static_cast<size_t>(j)]] = FiniteOrNull(values(j));
  }
  return out;
}

nlohmann::json TipJson(const TipErrors& tip) {
  return {{"mean", tip.mean}, {"std", tip.std}, {"max", tip.max}, {"per_pose", tip.percent}};
}

nlohmann::json MethodJson(const MethodResult& result) {
  const StiffnessEstimate& e = result.estimate;
  nlohmann::json residuals = nlohmann::json::object();
  for (int j = 0; j < 4; ++j) {
    residuals[kConfigurationNames[static_cast<size_t>(j)]] = FiniteOrNull(e.residual_rms(j));
  }
  return {{"method", e.method},
          {"valid", e.valid},
          {"message", e.message},
          {"stiffness", StiffnessJson(e.stiffness)},
          {"stiffness_std", StiffnessJson(e.standard_deviation)},
          {"residual_rms", residuals},
          {"tip_error_percent", TipJson(result.tip_errors)},
          {"warnings", e.warnings}};
}

std::string Cell(double value) {
  std::ostringstream out;
  out << std::setprecision(4) << value;
  return out.str();
}

std::string CellWithStd(double value, double std_dev) {
  std::ostringstream out;
  out << Cell(value) << " +- ";
  if (std::isfinite(std_dev)) {
    out << std::setprecision(2) << std_dev;
  } else {
    out << "inf";
  }
  return out.str();
}

void PrintRow(std::ostream& out, const std::string& label, const std::vector<std::string>& cells) {
  out << std::left << std::setw(16) << label;
  for (const std::string& cell : cells) out << std::setw(24) << cell;
  out << "\n";
}

std::vector<std::string> StiffnessCells(const StiffnessVector& values,
                                        const StiffnessVector& std_dev) {
  std::vector<std::string> cells;
  for (int j = 0; j < 4; ++j) cells.push_back(CellWithStd(values(j), std_dev(j)));
  return cells;
}

void PrintTipRow(std::ostream& out, const std::string& label, const TipErrors& tip,
                 bool valid = true) {
  if (!valid) {
    out << std::left << std::setw(16) << label << "(no valid estimate)\n";
    return;
  }
  out << std::left << std::setw(16) << label << std::right << std::fixed << std::setprecision(2)
      << std::setw(8) << tip.mean << std::setw(8) << tip.std << std::setw(8) << tip.max << "\n"
      << std::defaultfloat;
}

std::string Label(const MethodResult& result, bool primary) {
  return result.estimate.method + (primary ? " *" : "");
}

}  // namespace

nlohmann::json ReportToJson(const EstimateReport& report) {
  const MethodResult& primary = report.methods.at(report.primary);
  nlohmann::json methods = nlohmann::json::array();
  for (const MethodResult& result : report.methods) methods.push_back(MethodJson(result));
  return {{"stiffness", StiffnessJson(primary.estimate.stiffness)},
          {"stiffness_std", StiffnessJson(primary.estimate.standard_deviation)},
          {"method", primary.estimate.method},
          // The headline figure is a plain number (the mean over the poses);
          // the spread and each pose's error are beside it.
          {"tip_error_percent", primary.tip_errors.mean},
          {"tip_error_percent_detail", TipJson(primary.tip_errors)},
          {"warnings", primary.estimate.warnings},
          {"poses", report.num_poses},
          {"model", report.model_source},
          {"data", report.data_source},
          {"distal_length", report.distal_length},
          {"nominal",
           {{"stiffness", StiffnessJson(report.nominal)},
            {"tip_error_percent", TipJson(report.nominal_tip_errors)}}},
          {"estimates", methods}};
}

void PrintReport(const EstimateReport& report, std::ostream& out) {
  out << "shapesense estimate: " << report.num_poses << " poses from " << report.data_source
      << ", model " << report.model_source << "\n\n";
  PrintRow(out, "stiffness", {kStiffnessNames.begin(), kStiffnessNames.end()});
  PrintRow(out, "", {"N*mm^2", "N*mm^2", "N", "N"});
  PrintRow(out, "nominal",
           {Cell(report.nominal(0)), Cell(report.nominal(1)), Cell(report.nominal(2)),
            Cell(report.nominal(3))});
  for (size_t i = 0; i < report.methods.size(); ++i) {
    const StiffnessEstimate& e = report.methods[i].estimate;
    PrintRow(out, Label(report.methods[i], i == report.primary),
             StiffnessCells(e.stiffness, e.standard_deviation));
  }
  out << "\ntip error, % of the distal length (" << report.distal_length << " mm)\n"
      << std::left << std::setw(16) << "model" << std::right << std::setw(8) << "mean"
      << std::setw(8) << "std" << std::setw(8) << "max"
      << "\n";
  PrintTipRow(out, "nominal", report.nominal_tip_errors);
  for (size_t i = 0; i < report.methods.size(); ++i) {
    PrintTipRow(out, Label(report.methods[i], i == report.primary), report.methods[i].tip_errors,
                report.methods[i].estimate.valid);
  }
  out << "(* the estimate written as \"stiffness\")\n";
  for (const MethodResult& result : report.methods) {
    if (!result.estimate.valid) {
      out << "warning: " << result.estimate.method << ": failed: " << result.estimate.message
          << "\n";
    }
    for (const std::string& warning : result.estimate.warnings) {
      out << "warning: " << result.estimate.method << ": " << warning << "\n";
    }
  }
}

}  // namespace shapesense
