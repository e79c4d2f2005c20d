// A small SVG scatter plot for the benchmark reports: log-scaled axes, one colour per series, the
// Pareto front circled.
#pragma once

#include <string>
#include <vector>

namespace cli {

struct ScatterPoint {
  double x = 0, y = 0;
  int series = 0;      // index into ScatterPlot::series
  bool front = false;  // circled
};

struct ScatterPlot {
  std::string title, x_label, y_label;
  std::vector<std::string> series;  // legend entries, in colour order
  std::vector<ScatterPoint> points;
};

/// Writes the plot to `path` (points with x or y <= 0 or not finite are left out).
void write_scatter_svg(const ScatterPlot& plot, const std::string& path);

/// Marks the points no other point beats on both coordinates (smaller is better).
void mark_pareto_front(std::vector<ScatterPoint>& points);

}  // namespace cli
