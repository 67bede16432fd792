// The knobs' rows at work: their values, ranges and refusals (see encoder_params.h).
#include "encode/encoder_params.h"

#include <fmt/format.h>

#include <cmath>

#include "util/error.h"
#include "util/text.h"

namespace raysort {

double EncoderParam::value(const EncoderParams& p) const {
  return std::visit([&](auto member) { return static_cast<double>(p.*member); }, field);
}

bool EncoderParam::is_default(const EncoderParams& p) const { return value(p) == value(EncoderParams{}); }

std::string EncoderParam::valid_values() const { return number_range_text(lo, hi, whole()); }

const EncoderParam& encoder_param(std::string_view key) {
  for (const EncoderParam& row : encoder_params())
    if (row.key == key) return row;
  throw Error(fmt::format("encoder_param: no knob '{}'", key));
}

void copy_param(const EncoderParam& row, const EncoderParams& from, EncoderParams& to) {
  std::visit([&](auto member) { to.*member = from.*member; }, row.field);
}

std::string params_problem(const EncoderParams& p) {
  for (const EncoderParam& row : encoder_params()) {
    const double v = row.value(p);
    if (row.is_default(p) || (std::isfinite(v) && v >= row.lo && v <= row.hi)) continue;
    return fmt::format("{} {} is not valid: give {}", row.flag, row.whole() ? fmt::format("{:.0f}", v) : fmt::format("{:g}", v),
                       row.valid_values());
  }
  return "";
}

}  // namespace raysort
