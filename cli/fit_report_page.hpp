// The report of `pindrag fit` as a small self-contained HTML page (`--report-html`): the summary,
// a plot of the marker error over time (inline SVG; flagged frames marked), the markers by mean
// error and the segment scales. It reads the JSON report (cli/fit_report.hpp), nothing else.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace cli {

/// The page for `report`, titled after `trial` (a file name; escaped).
std::string fit_report_html(const nlohmann::json& report, const std::string& trial);

}  // namespace cli
