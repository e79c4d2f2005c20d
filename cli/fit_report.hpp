// The report of `pindrag fit` (docs/marker-fitting.md) as JSON:
//   {"mean_error": m, "markers": {"LASI": {"link", "mean", "max", "missing"}, ...},
//    "frames": [{"rms", "present", "flagged"}], "scales": {"<link>": factor},
//    "us_per_frame": µs, ...}
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "core/model.hpp"
#include "ik/marker_fit.hpp"
#include "ik/marker_set.hpp"

namespace cli {

struct FitReportInput {
  const core::Model* model = nullptr;
  const ik::MarkerSet* set = nullptr;  // the set the fit used (estimated offsets)
  const ik::MarkerFitResult* result = nullptr;
  std::vector<double> scales;             // per link (njoints); empty: all 1
  std::vector<double> calibration_rms;    // per calibration round (m)
  std::vector<std::string> not_in_trial;  // markers of the set the trial lacks
  double calibration_us = 0;
};

nlohmann::json fit_report(const FitReportInput& in);

}  // namespace cli
