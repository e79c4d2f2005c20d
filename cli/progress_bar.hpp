// A one-line progress bar on stderr for long conversions; silent unless stderr is a terminal.
#pragma once

#include <string>

namespace cli {

class ProgressBar {
 public:
  /// Draws only when `enabled` and stderr is a terminal.
  ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// Fraction done in [0, 1]; redraws only when the shown percentage changes.
  void update(double fraction);
  /// Ends the line (also done by the destructor).
  void finish();
  bool shown() const { return enabled_; }

 private:
  std::string label_;
  bool enabled_;
  int last_percent_ = -1;
  bool drawn_ = false;
};

}  // namespace cli
