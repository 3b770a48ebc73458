// How report, demo and report.html word a partially linear SVR's kernel check: which way
// it went, both nested CV figures, and the margin it was held to.
#include <gtest/gtest.h>

#include <string>

#include "thermodrift/models/fit_record.hpp"
#include "thermodrift/report/report.hpp"

namespace thermodrift {
namespace {

TEST(KernelCheckText, NamesTheOutcomeBothFiguresAndTheMargin) {
  KernelCheckRecord check;
  check.folds = 10;
  check.with_kernel_mse = 0.0004312;
  check.linear_part_mse = 0.0004263;
  check.min_gain = 0.1;
  check.kept = false;
  EXPECT_EQ(kernel_check_text(to_json(check)),
            "left out: nested 10-fold CV MSE 0.0004312 (°/h)² against the linear part's 0.0004263, not 10 % lower; "
            "the model is its linear part");
  check.with_kernel_mse = 0.0002;
  check.kept = true;
  EXPECT_EQ(kernel_check_text(to_json(check)),
            "kept: nested 10-fold CV MSE 0.0002 (°/h)² against the linear part's 0.0004263");
}

}  // namespace
}  // namespace thermodrift
