#pragma once
// model_params_t fixtures: model_params(k) is a valid set of kind k % 4 (MEM, PI, Katalenic,
// linear), its numbers a function of k; the other kinds' fields left at 0.

#include <cstdint>
#include <limits>
#include <string>

#include "hystloop/model_params_t.hpp"

namespace hystloop::fixtures {

inline model_params_t model_params(std::int64_t k) {
  model_params_t m{};
  m.format_version = model_params_t::FORMAT_VERSION;
  m.utime = 1'700'000'000'000'000 + 3'000'000 * k;
  m.version = static_cast<std::int32_t>(1 + k);
  m.publisher_id = k % 5 == 0 ? 0 : 0x600d'0000'0000 + k;
  m.kind = static_cast<std::int8_t>(k % 4);
  const double dk = static_cast<double>(k);
  switch (m.kind) {
    case model_params_t::KIND_MEM:
      m.mem_c1 = 5.0e-9 + 1e-11 * dk;
      m.mem_c2 = 1.7e-12;
      m.mem_c3 = 1.2;
      break;
    case model_params_t::KIND_PI:
      m.n_operators = static_cast<std::int32_t>(1 + k % model_params_t::MAX_OPERATORS);
      for (std::int32_t i = 0; i < m.n_operators; ++i) {
        m.pi_thresholds_V.push_back(16.5 * i);
        m.pi_weights.push_back(i == 0 ? 5.0e-9 : 2.0e-10 / (1.0 + i));
      }
      break;
    case model_params_t::KIND_KATALENIC:
      m.kat_k1 = 40.0 + dk;
      m.kat_k2 = 0.01;
      m.kat_k2_domain_min = -250.0;
      m.kat_k2_domain_max = 250.0;
      m.kat_in_shaping = model_params_t::SHAPING_LINEAR;
      m.kat_in_gain = 1.0;
      m.kat_in_domain_min = -1.0;
      m.kat_in_domain_max = 1.0;
      m.kat_in_amplitude = 1.0;
      m.kat_in_scale = 1.0;
      m.kat_out_shaping = model_params_t::SHAPING_POLYNOMIAL;
      m.kat_out_coefficients[1] = 3.79e-9;
      m.kat_out_coefficients[3] = 1.0e-15;
      m.kat_out_domain_min = -300.0;
      m.kat_out_domain_max = 300.0;
      m.kat_out_gain = 1.0;
      m.kat_out_amplitude = 1.0;
      m.kat_out_scale = 1.0;
      break;
    default:
      m.linear_gain = 6.34e-9;
      m.linear_offset_m = -1.0e-8 * dk;
      break;
  }
  m.residual_m = 2.1e-9;
  m.heldout_rms_m = k % 3 == 0 ? std::numeric_limits<double>::quiet_NaN() : 2.5e-9;
  m.samples_used = 20000 + k;
  m.window_s = 2.0;
  m.valid = true;
  m.source = "reident@host-" + std::to_string(k);
  return m;
}

}  // namespace hystloop::fixtures
