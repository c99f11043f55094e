// The ocular MPE against worked values of ANSI Z136.1-2014 Table 5a (IEC 60825-1:2014 Table
// A.1). Each expected value is worked by hand in its comment from the table row; the
// tolerance is rounding of the factors only (1e-9 relative) unless the row itself rounds.
#include "hazard/mpe.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace glint {
namespace {

constexpr double kRel = 1e-9;

void expectMpe(double nm, double t, double expected_w_m2, MpeLimit limit) {
  const Mpe m = ocularMpe(nm, t);
  EXPECT_NEAR(m.irradiance_w_m2, expected_w_m2, kRel * expected_w_m2)
      << nm << " nm, " << t << " s (" << m.rule << ")";
  EXPECT_NEAR(m.radiant_exposure_j_m2, expected_w_m2 * t, kRel * expected_w_m2 * t)
      << nm << " nm, " << t << " s: H = E t";
  EXPECT_EQ(m.limit, limit) << nm << " nm, " << t << " s (" << m.rule << ")";
}

TEST(Mpe, VisibleAtTheAversionResponse) {
  // 1.8 t^0.75 mJ/cm² at 0.25 s: 18 × 0.25^0.75 J/m² over 0.25 s = 18 × 0.25^-0.25
  // = 25.456 W/m², the familiar 2.5 mW/cm².
  expectMpe(532.0, 0.25, 18.0 * std::pow(0.25, -0.25), MpeLimit::Thermal);
  EXPECT_NEAR(ocularMpe(632.8, 0.25).irradiance_w_m2, 25.456, 0.001) << "the textbook value";
  expectMpe(400.0, 0.25, 25.45584412271571, MpeLimit::Thermal);
  expectMpe(700.0, 0.25, 25.45584412271571, MpeLimit::Thermal);
}

TEST(Mpe, VisibleThermalBeyondTenSecondsIsTenWattsPerSquareMetre) {
  // 1 mW/cm² = 10 W/m² from 10 s on; at 532 nm the photochemical limit is higher
  // (C_B = 10^(0.02 × 82) = 43.65: 100 C_B / t = 436.5 W/m² at 10 s, C_B W/m² at 1000 s).
  expectMpe(532.0, 10.0, 10.0, MpeLimit::Thermal);
  expectMpe(532.0, 1000.0, 10.0, MpeLimit::Thermal);
  expectMpe(650.0, 3.0e4, 10.0, MpeLimit::Thermal);
  // Continuity at 10 s: 18 × 10^-0.25 = 10.12 W/m² just below.
  EXPECT_NEAR(ocularMpe(532.0, 9.999).irradiance_w_m2, 18.0 * std::pow(9.999, -0.25), 1e-9)
      << "5e-6 to 10 s row";
}

TEST(Mpe, BlueLightIsLimitedPhotochemicallyOverLongExposures) {
  // 450 nm, C_B = 1: 100 J/m² over 10–100 s; 1 W/m² from 100 s. At 50 s: 100 / 50 = 2 W/m²,
  // below the thermal 10 W/m².
  expectMpe(450.0, 50.0, 2.0, MpeLimit::Photochemical);
  expectMpe(450.0, 1000.0, 1.0, MpeLimit::Photochemical);
  // At 10 s the two limits meet: 100 J/m² / 10 s = 10 W/m². The thermal one is reported.
  EXPECT_NEAR(ocularMpe(440.0, 10.0).irradiance_w_m2, 10.0, 1e-9);
  // At 550 nm (C_B = 100) thermal wins; at 480 nm (C_B = 10^0.6 = 3.98) photochemistry.
  expectMpe(550.0, 1000.0, 10.0, MpeLimit::Thermal);
  expectMpe(480.0, 1000.0, std::pow(10.0, 0.02 * 30.0), MpeLimit::Photochemical);
}

TEST(Mpe, NearInfraredCarriesItsCorrectionFactors) {
  // 808 nm: C_A = 10^(0.002 × 108) = 1.6444; at 0.25 s 25.456 × C_A.
  const double ca = std::pow(10.0, 0.002 * 108.0);
  expectMpe(808.0, 0.25, 18.0 * ca * std::pow(0.25, -0.25), MpeLimit::Thermal);
  // 1064 nm, C_C = 1: 9.0 t^0.75 mJ/cm² → 90 × 0.25^-0.25 = 127.28 W/m² at 0.25 s; 50 W/m²
  // (5 mW/cm²) from 10 s.
  expectMpe(1064.0, 0.25, 90.0 * std::pow(0.25, -0.25), MpeLimit::Thermal);
  expectMpe(1064.0, 100.0, 50.0, MpeLimit::Thermal);
  // 1300 nm, C_C = 8: 400 W/m² from 10 s.
  expectMpe(1300.0, 100.0, 400.0, MpeLimit::Thermal);
  // 1175 nm: C_C = 10^(0.018 × 25) = 2.818.
  expectMpe(1175.0, 100.0, 50.0 * std::pow(10.0, 0.45), MpeLimit::Thermal);
}

TEST(Mpe, FarInfraredBeyondTenSecondsIsAThousandWattsPerSquareMetre) {
  // 0.1 W/cm² for 1.4 µm – 1 mm from 10 s on.
  for (double nm : {1450.0, 1550.0, 2000.0, 10600.0, 1.0e6}) {
    expectMpe(nm, 100.0, 1000.0, MpeLimit::Thermal);
  }
  // 10.6 µm at 1 s: 0.56 t^0.25 J/cm² = 5600 J/m² → 5600 W/m².
  expectMpe(10600.0, 1.0, 5600.0, MpeLimit::Thermal);
  // 1550 nm at 1 s: 1 J/cm² = 1e4 J/m² → 1e4 W/m².
  expectMpe(1550.0, 1.0, 1.0e4, MpeLimit::Thermal);
  // 1450 nm at 1e-4 s: 0.1 J/cm² → 1000 J/m² / 1e-4 s = 1e7 W/m².
  expectMpe(1450.0, 1.0e-4, 1.0e7, MpeLimit::Thermal);
}

TEST(Mpe, ShortPulsesUseTheConstantRadiantExposureRows) {
  // 532 nm, 10 ns: 2.0e-7 J/cm² = 2e-3 J/m² → 2e5 W/m² over 1e-8 s.
  expectMpe(532.0, 1.0e-8, 2.0e5, MpeLimit::Thermal);
  // 1064 nm, 10 ns: 2.0e-6 J/cm² = 2e-2 J/m² → 2e6 W/m².
  expectMpe(1064.0, 1.0e-8, 2.0e6, MpeLimit::Thermal);
  // The rows meet: 18 (5e-6)^0.75 = 1.90e-3 J/m² against 2e-3 (the standard rounds).
  EXPECT_NEAR(ocularMpe(532.0, 5e-6).radiant_exposure_j_m2, 2e-3, 0.06 * 2e-3);
}

TEST(Mpe, BandEdgesTakeTheLowerLimit) {
  // 1400 nm is named by the retinal row (50 C_C = 400 W/m²) and the corneal one (1000 W/m²).
  expectMpe(1400.0, 100.0, 400.0, MpeLimit::Thermal);
  // 1050 nm: 10 C_A = 50 W/m² (C_A = 5 from 1050 nm) and 50 C_C = 50 W/m²: no jump.
  expectMpe(1050.0, 100.0, 50.0, MpeLimit::Thermal);
}

TEST(Mpe, OutsideTheTableIsRefusedNotExtrapolated) {
  EXPECT_THROW(ocularMpe(399.9, 0.25), std::out_of_range) << "ultraviolet";
  EXPECT_THROW(ocularMpe(1.0e6 + 1.0, 0.25), std::out_of_range) << "beyond 1 mm";
  EXPECT_THROW(ocularMpe(532.0, 0.5e-9), std::out_of_range) << "shorter than 1 ns";
  EXPECT_THROW(ocularMpe(532.0, 3.1e4), std::out_of_range) << "longer than 3e4 s";
  EXPECT_THROW(ocularMpe(std::nan(""), 0.25), std::out_of_range) << "NaN";
  try {
    ocularMpe(350.0, 0.25);
    ADD_FAILURE() << "350 nm was accepted";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("400 nm to 1 mm"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace glint
