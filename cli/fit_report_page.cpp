#include "cli/fit_report_page.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

namespace cli {

namespace {

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

// Marker RMS error (mm) per frame against time (s): a polyline over the fitted frames, flagged
// frames as red ticks on the time axis, the mean as a dashed line.
std::string error_plot(const nlohmann::json& report) {
  const nlohmann::json& frames = report.at("frames");
  const double dt = report.value("frame_time", 1.0 / 120.0);
  const int n = static_cast<int>(frames.size());
  double top = 1e-3;
  for (const auto& f : frames) {
    if (!f.at("flagged").get<bool>()) top = std::max(top, f.at("rms").get<double>() * 1000);
  }
  top = std::ceil(top / 5) * 5;
  constexpr double kChartWidth = 720, kChartHeight = 250, kMarginLeft = 50, kMarginBottom = 30,
                   kMarginTop = 20, kMarginRight = 24;
  const double duration = std::max(dt * std::max(n - 1, 1), 1e-9);
  const auto x_of = [&](int f) {
    return kMarginLeft + (kChartWidth - kMarginLeft - kMarginRight) * (f * dt) / duration;
  };
  const auto y_of = [&](double mm) {
    return kChartHeight - kMarginBottom - (kChartHeight - kMarginBottom - kMarginTop) * mm / top;
  };
  std::string svg = "<svg xmlns='http://www.w3.org/2000/svg' width='" + fixed(kChartWidth, 0) +
                    "' height='" + fixed(kChartHeight, 0) +
                    "' font-family='sans-serif' font-size='11'>";
  // axes and ticks
  svg += "<line x1='" + fixed(kMarginLeft, 1) + "' y1='" + fixed(y_of(0), 1) + "' x2='" +
         fixed(kChartWidth - kMarginRight, 1) + "' y2='" + fixed(y_of(0), 1) + "' stroke='#444'/>";
  svg += "<line x1='" + fixed(kMarginLeft, 1) + "' y1='" + fixed(kMarginTop, 1) + "' x2='" +
         fixed(kMarginLeft, 1) + "' y2='" + fixed(y_of(0), 1) + "' stroke='#444'/>";
  for (int k = 0; k <= 4; ++k) {
    const double mm = top * k / 4;
    svg += "<text x='" + fixed(kMarginLeft - 6, 1) + "' y='" + fixed(y_of(mm) + 4, 1) +
           "' text-anchor='end'>" + fixed(mm, mm < 10 ? 1 : 0) + "</text>";
    const double t = duration * k / 4;
    svg += "<text x='" +
           fixed(kMarginLeft + (kChartWidth - kMarginLeft - kMarginRight) * k / 4, 1) + "' y='" +
           fixed(kChartHeight - 12, 1) + "' text-anchor='middle'>" + fixed(t, 1) + " s</text>";
  }
  svg += "<text x='" + fixed(kMarginLeft - 6, 1) + "' y='12' text-anchor='end'>mm</text>";
  // the error, broken at flagged frames
  std::string path;
  bool pen = false;
  for (int f = 0; f < n; ++f) {
    if (frames[f].at("flagged").get<bool>()) {
      pen = false;
      svg += "<line x1='" + fixed(x_of(f), 1) + "' y1='" + fixed(y_of(0), 1) + "' x2='" +
             fixed(x_of(f), 1) + "' y2='" + fixed(y_of(0) - 6, 1) + "' stroke='#d33'/>";
      continue;
    }
    path += (pen ? " L" : " M") + fixed(x_of(f), 1) + " " +
            fixed(y_of(frames[f].at("rms").get<double>() * 1000), 1);
    pen = true;
  }
  svg += "<path d='" + path + "' fill='none' stroke='#1f77b4' stroke-width='1.2'/>";
  const double mean = report.at("mean_error").get<double>() * 1000;
  svg += "<line x1='" + fixed(kMarginLeft, 1) + "' y1='" + fixed(y_of(mean), 1) + "' x2='" +
         fixed(kChartWidth - kMarginRight, 1) + "' y2='" + fixed(y_of(mean), 1) +
         "' stroke='#ff7f0e' stroke-dasharray='4 3'/>";
  svg += "</svg>";
  return svg;
}

}  // namespace

std::string fit_report_html(const nlohmann::json& report, const std::string& trial) {
  std::string html =
      "<!doctype html><html><head><meta charset='utf-8'><title>pindrag fit: " + escape(trial) +
      "</title><style>body{font-family:sans-serif;margin:24px;color:#222}"
      "table{border-collapse:collapse}td,th{padding:2px 10px;text-align:right}"
      "th{border-bottom:1px solid #999}td:first-child,th:first-child{text-align:left}"
      "</style></head><body>";
  html += "<h1>" + escape(trial) + " on " + escape(report.value("character", "?")) + "</h1>";
  const int fitted = report.value("frames_fitted", 0), flagged = report.value("frames_flagged", 0);
  html += "<p>Mean marker error <b>" + fixed(report.at("mean_error").get<double>() * 1000, 2) +
          " mm</b> over " + std::to_string(fitted) + " fitted frames (" + std::to_string(flagged) +
          " flagged: too few markers), " + fixed(report.value("us_per_frame", 0.0), 0) +
          " µs per frame.</p>";
  if (report.contains("second_starts")) {
    const nlohmann::json& s = report.at("second_starts");
    html +=
        "<p>Frames fitted a second time from their unbounded fit (error above the restart "
        "threshold): " +
        std::to_string(s.value("tried", 0)) + ", of which " + std::to_string(s.value("kept", 0)) +
        " kept the second fit.</p>";
  }
  html +=
      "<h2>Marker error over time</h2><p>RMS over the markers present in each frame; the "
      "dashed line is the mean, red ticks mark flagged frames.</p>" +
      error_plot(report);
  // markers, worst first
  std::vector<std::pair<std::string, nlohmann::json>> markers;
  for (const auto& [name, m] : report.at("markers").items()) markers.emplace_back(name, m);
  std::sort(markers.begin(), markers.end(), [](const auto& a, const auto& b) {
    return a.second.at("mean").template get<double>() > b.second.at("mean").template get<double>();
  });
  html +=
      "<h2>Markers</h2><table><tr><th>marker</th><th>link</th><th>mean (mm)</th>"
      "<th>max (mm)</th><th>missing frames</th></tr>";
  for (const auto& [name, m] : markers) {
    html += "<tr><td>" + escape(name) + "</td><td>" + escape(m.at("link").get<std::string>()) +
            "</td><td>" + fixed(m.at("mean").get<double>() * 1000, 1) + "</td><td>" +
            fixed(m.at("max").get<double>() * 1000, 1) + "</td><td>" +
            std::to_string(m.at("missing").get<int>()) + "</td></tr>";
  }
  html += "</table><h2>Segment scales</h2><table><tr><th>link</th><th>scale</th></tr>";
  for (const auto& [link, s] : report.at("scales").items()) {
    if (std::abs(s.get<double>() - 1.0) < 1e-12) continue;
    html += "<tr><td>" + escape(link) + "</td><td>" + fixed(s.get<double>(), 3) + "</td></tr>";
  }
  html += "</table></body></html>\n";
  return html;
}

}  // namespace cli
