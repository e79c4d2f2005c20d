#include "cli/svg_scatter.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

namespace cli {

namespace {

constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd"};
constexpr int kW = 720, kH = 440, kLeft = 80, kRight = 190, kTop = 40, kBottom = 60;

bool plotted(const ScatterPoint& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && p.x > 0 && p.y > 0;
}

std::string svg_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

}  // namespace

void mark_pareto_front(std::vector<ScatterPoint>& points) {
  for (ScatterPoint& a : points) {
    a.front = plotted(a) && std::none_of(points.begin(), points.end(), [&](const ScatterPoint& b) {
                return plotted(b) && b.x <= a.x && b.y <= a.y && (b.x < a.x || b.y < a.y);
              });
  }
}

void write_scatter_svg(const ScatterPlot& plot, const std::string& path) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const ScatterPoint& p : plot.points) {
    if (!plotted(p)) continue;
    x0 = std::min(x0, std::log10(p.x));
    x1 = std::max(x1, std::log10(p.x));
    y0 = std::min(y0, std::log10(p.y));
    y1 = std::max(y1, std::log10(p.y));
  }
  if (x0 > x1) x0 = 0, x1 = 1;
  if (y0 > y1) y0 = 0, y1 = 1;
  x0 = std::floor(x0), x1 = std::ceil(x1 + 1e-9), y0 = std::floor(y0), y1 = std::ceil(y1 + 1e-9);
  const double pw = kW - kLeft - kRight, ph = kH - kTop - kBottom;
  auto X = [&](double v) { return kLeft + (std::log10(v) - x0) / (x1 - x0) * pw; };
  auto Y = [&](double v) { return kTop + (1 - (std::log10(v) - y0) / (y1 - y0)) * ph; };
  std::ofstream o(path);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << kLeft << "\" y=\"22\" font-size=\"15\">" << plot.title << "</text>\n";
  for (double d = x0; d <= x1; ++d) {
    const double x = kLeft + (d - x0) / (x1 - x0) * pw;
    o << "<line x1=\"" << x << "\" y1=\"" << kTop << "\" x2=\"" << x << "\" y2=\"" << kTop + ph
      << "\" stroke=\"#ddd\"/><text x=\"" << x << "\" y=\"" << kTop + ph + 16
      << "\" text-anchor=\"middle\">" << svg_number(std::pow(10, d)) << "</text>\n";
  }
  for (double d = y0; d <= y1; ++d) {
    const double y = kTop + (1 - (d - y0) / (y1 - y0)) * ph;
    o << "<line x1=\"" << kLeft << "\" y1=\"" << y << "\" x2=\"" << kLeft + pw << "\" y2=\"" << y
      << "\" stroke=\"#ddd\"/><text x=\"" << kLeft - 6 << "\" y=\"" << y + 4
      << "\" text-anchor=\"end\">" << svg_number(std::pow(10, d)) << "</text>\n";
  }
  o << "<text x=\"" << kLeft + pw / 2 << "\" y=\"" << kH - 16 << "\" text-anchor=\"middle\">"
    << plot.x_label << "</text>\n<text transform=\"translate(18," << kTop + ph / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << plot.y_label << "</text>\n";
  for (const ScatterPoint& p : plot.points) {
    if (!plotted(p)) continue;
    o << "<circle cx=\"" << X(p.x) << "\" cy=\"" << Y(p.y) << "\" r=\"4\" fill=\""
      << kColours[p.series % 5] << "\"/>\n";
    if (p.front) {
      o << "<circle cx=\"" << X(p.x) << "\" cy=\"" << Y(p.y)
        << "\" r=\"8\" fill=\"none\" stroke=\"black\"/>\n";
    }
  }
  for (size_t k = 0; k < plot.series.size(); ++k) {
    const double y = kTop + 10 + 18 * static_cast<double>(k);
    o << "<circle cx=\"" << kW - kRight + 20 << "\" cy=\"" << y << "\" r=\"4\" fill=\""
      << kColours[k % 5] << "\"/><text x=\"" << kW - kRight + 30 << "\" y=\"" << y + 4 << "\">"
      << plot.series[k] << "</text>\n";
  }
  const double y = kTop + 10 + 18 * static_cast<double>(plot.series.size());
  o << "<circle cx=\"" << kW - kRight + 20 << "\" cy=\"" << y
    << "\" r=\"8\" fill=\"none\" stroke=\"black\"/><text x=\"" << kW - kRight + 30 << "\" y=\""
    << y + 4 << "\">Pareto front</text>\n</svg>\n";
}

}  // namespace cli
