// The simulated plant's sensors (host_sim/plant_hal.hpp, SensorConfig): each feature alone against
// an analytic expectation. The default sensors read exactly what the ideal plant read before them;
// per-joint encoder resolution, the wrist coupling (counts and torques through C), encoder edge
// jitter, a coarser DAC, the potentiometers, the index pulses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "hal/hal.hpp"
#include "osc/runtime/io.hpp"
#include "plant_hal.hpp"
#include "test_util.hpp"

using namespace sim;

namespace {

Vec6 q_start() { return osc::joint_vector<double>(osc::robot::kQStart); }
double gear(int i) { return osc::robot::kArm.links[i].gear_ratio; }
/// Joint radians of one motor revolution.
double motor_rev(int i) { return 2 * osc::kPi / std::abs(gear(i)); }
/// The Trident encoders' resolution without their coupling (the resolution alone).
osc::EncoderMap trident_resolution() {
  osc::EncoderMap m = osc::robot::kDriveTrain.encoders;
  m.coupling_terms = 0;
  return m;
}

TEST(PlantSensors, DefaultSensorsReadExactlyTodaysEncodersAndDacs) {
  // Today's arithmetic: floor((q - q_start) * counts_per_rad(i, cpr)), code_to_torque(code).
  osc::test::RandomStates rs;
  Plant plant;
  const Vec6 q0 = q_start();
  for (const double cpr : {osc::robot::kDrives.encoder_counts_per_motor_rev, 2000.0, 333.0}) {
    const SensorConfig s =
        cpr == osc::robot::kDrives.encoder_counts_per_motor_rev ? SensorConfig{} : sensors_with_resolution(cpr);
    for (int i = 0; i < 6; ++i) EXPECT_EQ(s.encoders.counts_per_rad[i], osc::counts_per_rad(i, cpr)) << i;
    PlantHal hal(plant, q0, s);
    int differ = 0, n = 0;
    for (int k = 0; k < 5000; ++k) {
      // Random poses, and poses a few counts from the start (where an edge matters most).
      const Vec6 q = k % 2 ? rs.q_nonsingular() : Vec6(q0 + rs.vec(20.0 / osc::counts_per_rad(0, cpr)));
      plant.reset(q);
      std::int32_t counts[6];
      ASSERT_TRUE(hal.read_encoders(counts));
      for (int i = 0; i < 6; ++i, ++n)
        differ += counts[i] != static_cast<std::int32_t>(std::floor((q(i) - q0(i)) * osc::counts_per_rad(i, cpr)));
    }
    std::printf("default sensors, %.0f counts/rev: %d of %d readings differ from today's formula\n", cpr, differ, n);
    EXPECT_EQ(differ, 0);
  }
  // The DACs: every code gives code_to_torque's torque, bit for bit.
  PlantHal hal(plant, q0);
  int differ = 0;
  for (std::int32_t c = -osc::kDacMaxCode; c <= osc::kDacMaxCode; ++c) {
    const std::int32_t codes[6] = {c, c, c, c, c, c};
    hal.write_dacs(codes);
    const Vec6 t = hal.torque();
    for (int i = 0; i < 6; ++i) differ += t(i) != osc::code_to_torque(i, c);
  }
  EXPECT_EQ(differ, 0);
}

TEST(PlantSensors, PerJointResolutionCountsAMotorRevolution) {
  // The Trident encoders (coupling left out: the resolution alone): 1000 counts per motor
  // revolution on J1 and J3-J6, about 797 on J2. Ten motor revolutions of each joint in turn.
  SensorConfig s;
  s.encoders = trident_resolution();
  Plant plant;
  const Vec6 q0 = q_start();
  for (int j = 0; j < 6; ++j) {
    PlantHal hal(plant, q0, s);
    std::int32_t before[6], after[6];
    plant.reset(q0);
    hal.read_encoders(before);
    Vec6 q = q0;
    q(j) += 10 * motor_rev(j);
    plant.reset(q);
    hal.read_encoders(after);
    const double per_rev = (after[j] - before[j]) / 10.0;
    const double analytic = 2 * osc::kPi * s.encoders.counts_per_rad[j] / std::abs(gear(j));
    std::printf("J%d: %.1f counts per motor revolution (analytic %.3f)\n", j + 1, per_rev, analytic);
    EXPECT_LE(std::abs(after[j] - before[j] - 10 * analytic), 1.0);
    EXPECT_NEAR(analytic, j == 1 ? 797.0 : 1000.0, 1.0);  // the published scales have five digits
    for (int i = 0; i < 6; ++i)
      if (i != j) {
        EXPECT_EQ(after[i], before[i]) << "channel " << i << " moved with joint " << j;
      }
  }
}

TEST(PlantSensors, CoupledCountsRoundTripThroughTheFirmwaresMap) {
  // The Trident map with its wrist coupling. The plant's motors at C^-1 q; the HAL's counting
  // (encoder_count) and the firmware's angles_from_counts (IoMap) must invert each other.
  const osc::EncoderMap& map = osc::robot::kDriveTrain.encoders;
  const EncoderCoupling C(map);
  const osc::IoMap<double> io = osc::IoMap<double>::of(map);
  ASSERT_TRUE(C.coupled);
  // C C^-1 = I, and the same inverse as the firmware's.
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      double x = 0;
      for (int k = 0; k < 6; ++k) x += C.c[i][k] * C.inverse[k][j];
      EXPECT_NEAR(x, i == j ? 1.0 : 0.0, 1e-15);
      EXPECT_NEAR(C.inverse[i][j], io.inverse[i][j], 1e-15);
    }
  EXPECT_DOUBLE_EQ(C.c[5][4], -0.180556);
  EXPECT_NEAR(C.inverse[5][4], 0.180556, 1e-15);

  const Vec6 q0 = q_start();
  const Vec6 e0 = C.motor_from_joint(q0);
  osc::test::RandomStates rs;
  // Random poses: each motor's angle error within one count ([0, 1) count: floor), the joints'
  // within the counts their motors contribute, sum_k |C_jk| / counts_per_rad_k.
  double worst_motor = 0, worst_joint = 0;  // [counts of the channel / of the joint's own channel]
  for (int k = 0; k < 20000; ++k) {
    const Vec6 q = rs.q_nonsingular();
    const Vec6 e = C.motor_from_joint(q);
    std::int32_t counts[6];
    for (int i = 0; i < 6; ++i) counts[i] = encoder_count(e(i), e0(i), map.counts_per_rad[i]);
    const Vec6 back = osc::angles_from_counts<double>(q0, io, counts);
    const Vec6 motor_error = C.motor_from_joint(q) - C.motor_from_joint(back);
    for (int i = 0; i < 6; ++i) {
      const double m = motor_error(i) * map.counts_per_rad[i];
      ASSERT_GT(m, -1e-6) << k << " " << i;
      ASSERT_LT(m, 1 + 1e-6) << k << " " << i;
      worst_motor = std::max(worst_motor, m);
      double bound = 0;
      for (int j = 0; j <= i; ++j) bound += std::abs(C.c[i][j]) / map.counts_per_rad[j];
      ASSERT_LE(std::abs(q(i) - back(i)), bound + 1e-12) << k << " " << i;
      worst_joint = std::max(worst_joint, std::abs(q(i) - back(i)) * map.counts_per_rad[i]);
    }
  }
  std::printf("coupled round trip: motor-angle error up to %.6f counts, joint-angle error up to %.4f counts\n",
              worst_motor, worst_joint);
  // Count lattice points: counts -> angles -> counts. At a lattice point the motor sits on an
  // edge, where floor decides by round-off: the unfloored count is n to 1e-9 counts, and the
  // count with the edge moved by 1e-6 count is n exactly.
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> n_of(-200000, 200000);
  double worst_lattice = 0;
  int exact_unshifted = 0;
  const int kLattice = 20000;
  for (int k = 0; k < kLattice; ++k) {
    std::int32_t n[6], back[6];
    for (int i = 0; i < 6; ++i) n[i] = n_of(rng);
    const Vec6 e = C.motor_from_joint(osc::angles_from_counts<double>(q0, io, n));
    bool exact = true;
    for (int i = 0; i < 6; ++i) {
      worst_lattice = std::max(worst_lattice, std::abs((e(i) - e0(i)) * map.counts_per_rad[i] - n[i]));
      back[i] = encoder_count(e(i), e0(i), map.counts_per_rad[i], 1e-6);
      ASSERT_EQ(back[i], n[i]) << k << " " << i;
      exact = exact && encoder_count(e(i), e0(i), map.counts_per_rad[i]) == n[i];
    }
    exact_unshifted += exact;
  }
  std::printf(
      "lattice points: unfloored count within %.2e of n; counts -> angles -> counts exact at all %d (%d without "
      "the 1e-6 edge shift)\n",
      worst_lattice, kLattice, exact_unshifted);
  EXPECT_LT(worst_lattice, 1e-9);
}

TEST(PlantSensors, CoupledTorquesRoundTripWithinOneDacCode) {
  // Joint torques -> the firmware's motor torques (C^T tau) -> DAC codes -> the HAL's channel
  // torques -> C^-T (what a coupled plant applies) = the joint torques within one code's torque.
  const osc::EncoderMap& map = osc::robot::kDriveTrain.encoders;
  const osc::IoMap<double> io = osc::IoMap<double>::of(map);
  SensorConfig s;
  s.encoders = map;
  Plant plant;
  PlantHal hal(plant, q_start(), s);
  osc::test::RandomStates rs;
  double worst = 0;  // [codes of the joint]
  for (int k = 0; k < 20000; ++k) {
    Vec6 tau;
    for (int i = 0; i < 6; ++i) tau(i) = 0.8 * osc::robot::kDrives.torque_limit[i] * rs.u(rs.rng);
    const Vec6 tau_m = osc::motor_torques(io, tau);
    std::int32_t codes[6];
    for (int i = 0; i < 6; ++i) ASSERT_FALSE(osc::torque_to_code(i, tau_m(i), codes[i]));
    hal.write_dacs(codes);
    const Vec6 applied = hal.coupling().joint_from_motor_torques(hal.torque());
    for (int i = 0; i < 6; ++i) {
      const double lsb = osc::robot::kDrives.torque_limit[i] / static_cast<double>(osc::kDacMaxCode);
      worst = std::max(worst, std::abs(applied(i) - tau(i)) / lsb);
    }
  }
  std::printf("torque path through the coupling: joint torques back within %.3f DAC codes\n", worst);
  EXPECT_LT(worst, 1.0);
  // The coupling matters: without C^-T the wrist's torques are off by far more than a code.
  Vec6 tau = Vec6::Zero();
  tau(5) = 10;
  const Vec6 tau_m = osc::motor_torques(io, tau);
  EXPECT_NEAR(tau_m(4), -0.180556 * 10, 1e-12);
  EXPECT_NEAR(hal.coupling().joint_from_motor_torques(tau_m)(4), 0.0, 1e-12);
}

TEST(PlantSensors, EncoderJitterMovesTheEdgesSymmetrically) {
  constexpr double kJitter = 0.3;
  constexpr int kSamples = 20000;
  SensorConfig s;
  s.encoder_jitter = kJitter;
  Plant plant;
  const Vec6 q0 = q_start();
  // On an edge: n counts from the start on each joint, x = (q - q_start) * counts_per_rad = n up to
  // round-off. The reading alternates between n and n - 1 at random; it is on average x - 0.5, as
  // the ideal floor is over a count.
  {
    const int n[6] = {17, -5, 123, 0, -40, 3};
    Vec6 q = q0;
    for (int i = 0; i < 6; ++i) q(i) += n[i] / osc::counts_per_rad(i);
    plant.reset(q);
    PlantHal hal(plant, q0, s);
    long sum[6] = {}, low[6] = {}, changes[6] = {};
    std::int32_t prev[6] = {};
    double x[6];
    for (int i = 0; i < 6; ++i) x[i] = (q(i) - q0(i)) * osc::counts_per_rad(i);
    for (int k = 0; k < kSamples; ++k) {
      std::int32_t c[6];
      hal.read_encoders(c);
      for (int i = 0; i < 6; ++i) {
        ASSERT_TRUE(c[i] == n[i] || c[i] == n[i] - 1) << c[i] << " at edge " << n[i];
        sum[i] += c[i];
        low[i] += c[i] == n[i] - 1;
        if (k > 0) changes[i] += c[i] != prev[i];
        prev[i] = c[i];
      }
    }
    const double tol = 3 * 0.5 / std::sqrt(kSamples);  // Bernoulli(1/2): sigma 0.5
    for (int i = 0; i < 6; ++i) {
      const double mean_error = static_cast<double>(sum[i]) / kSamples - (x[i] - 0.5);
      const double f_low = static_cast<double>(low[i]) / kSamples,
                   f_change = static_cast<double>(changes[i]) / (kSamples - 1);
      std::printf("J%d on edge %d: %.4f of the readings at n - 1, %.4f change from the previous; mean error %+.4f\n",
                  i + 1, n[i], f_low, f_change, mean_error);
      EXPECT_NEAR(mean_error, 0.0, tol);
      EXPECT_NEAR(f_low, 0.5, tol);
      EXPECT_NEAR(f_change, 0.5, tol);  // independent samples: P(change) = 2 * 1/2 * 1/2
    }
  }
  // Random poses: the reading differs from the jitter-free one by at most a count, with
  // probability jitter / 2 (an edge within jitter of the position, either side: 2 * jitter^2 / 2 /
  // (2 jitter)), zero on average.
  {
    PlantHal ideal(plant, q0), jittered(plant, q0, s);
    osc::test::RandomStates rs;
    long differ = 0, sum = 0, n = 0;
    for (int k = 0; k < kSamples; ++k) {
      plant.reset(rs.q_nonsingular());
      std::int32_t a[6], b[6];
      ideal.read_encoders(a);
      jittered.read_encoders(b);
      for (int i = 0; i < 6; ++i, ++n) {
        ASSERT_LE(std::abs(b[i] - a[i]), 1);
        differ += b[i] != a[i];
        sum += b[i] - a[i];
      }
    }
    const double p = static_cast<double>(differ) / n, mean = static_cast<double>(sum) / n;
    std::printf("random poses: %.4f of the readings moved by the jitter (analytic %.3f), mean change %+.5f counts\n", p,
                kJitter / 2, mean);
    EXPECT_NEAR(p, kJitter / 2, 3 * std::sqrt(kJitter / 2 * (1 - kJitter / 2) / n));
    EXPECT_NEAR(mean, 0.0, 3 * std::sqrt(kJitter / 2 / n));
  }
}

TEST(PlantSensors, A12BitDacStepsEvery16Codes) {
  SensorConfig s;
  s.dac_bits = 12;
  Plant plant;
  PlantHal hal(plant, q_start(), s);
  // Sweep every code: the torque is a staircase of plateaus 16 codes wide, 16 codes' torque high,
  // to the nearest step (within 8 codes), inside the 12-bit DAC's range of +-2047 steps.
  for (int i = 0; i < 6; ++i) {
    const double lsb = osc::robot::kDrives.torque_limit[i] / static_cast<double>(osc::kDacMaxCode);
    std::vector<int> widths;
    int width = 0;
    double prev = 0, worst = 0, worst_end = 0;
    for (std::int32_t c = -osc::kDacMaxCode; c <= osc::kDacMaxCode; ++c) {
      std::int32_t codes[6] = {0, 0, 0, 0, 0, 0};
      codes[i] = c;
      hal.write_dacs(codes);
      const double t = hal.torque()(i);
      // To the nearest step inside the 12-bit range (+-32752), to its end beyond.
      double& w = std::abs(c) <= 32752 + 8 ? worst : worst_end;
      w = std::max(w, std::abs(t - osc::code_to_torque(i, c)) / lsb);
      if (c == 0) {
        EXPECT_EQ(t, 0.0);
      }
      if (c > -osc::kDacMaxCode && t != prev) {
        widths.push_back(width);
        EXPECT_NEAR(t - prev, 16 * lsb, 1e-9 * lsb) << c;
        width = 0;
      }
      ++width;
      prev = t;
    }
    widths.push_back(width);
    EXPECT_NEAR(prev, 2047 * 16 * lsb, 1e-9);
    // Inside the range every plateau is 16 codes; the end ones are cut by the 16-bit code range.
    int not16 = 0;
    for (size_t k = 1; k + 1 < widths.size(); ++k) not16 += widths[k] != 16;
    if (i == 0)
      std::printf(
          "12-bit DAC: %zu plateaus, interior ones all 16 codes wide (%d not), ends %d and %d codes; error up to %.1f "
          "codes (%.1f at the range's ends)\n",
          widths.size(), not16, widths.front(), widths.back(), worst, worst_end);
    EXPECT_EQ(widths.size(), 4095u);
    EXPECT_EQ(not16, 0);
    EXPECT_LE(worst, 8.0 + 1e-9);
    EXPECT_LE(worst_end, 15.0);  // -32767 -> -32752
  }
  EXPECT_EQ(dac_quantise(7, 12), 0);
  EXPECT_EQ(dac_quantise(8, 12), 16);
  EXPECT_EQ(dac_quantise(-8, 12), 0);
  EXPECT_EQ(dac_quantise(-9, 12), -16);
  EXPECT_EQ(dac_quantise(-osc::kDacMaxCode, 12), -32752);
  EXPECT_EQ(dac_quantise(12345, 16), 12345);
}

TEST(PlantSensors, PotentiometersScaleOffsetNoiseAndClamp) {
  constexpr int kSamples = 20000;
  SensorConfig s;
  s.pot_noise = 3.0;
  const double offset[6] = {2.5, -4.0, 0.0, 7.25, -1.5, 10.0};
  for (int i = 0; i < 6; ++i) s.pot_offset[i] = offset[i];
  Plant plant;
  const Vec6 q0 = q_start();
  plant.reset(q0);
  PlantHal hal(plant, q0, s);
  double sum[6] = {}, sum2[6] = {};
  for (int k = 0; k < kSamples; ++k) {
    std::uint16_t c[6];
    hal.read_pots(c);
    for (int i = 0; i < 6; ++i) {
      sum[i] += c[i];
      sum2[i] += static_cast<double>(c[i]) * c[i];
    }
  }
  for (int i = 0; i < 6; ++i) {
    const double mean = sum[i] / kSamples;
    const double sd = std::sqrt((sum2[i] - kSamples * mean * mean) / (kSamples - 1));
    const double expected = pot_scale(i, q0(i)) + offset[i];
    std::printf("J%d pot: mean %.3f (expected %.3f, %+.4f), sd %.4f (%+.2f %%)\n", i + 1, mean, expected,
                mean - expected, sd, 100 * (sd / s.pot_noise - 1));
    EXPECT_NEAR(mean, expected, 3 * s.pot_noise / std::sqrt(kSamples));
    EXPECT_NEAR(sd, s.pot_noise, 0.03 * s.pot_noise);
  }
  // The scale: joint angle at code 0 and full scale; pot_to_angle inverts it.
  const auto& d = osc::robot::kDriveTrain;
  ASSERT_EQ(d.pot_bits, 12);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(pot_scale(i, d.pot_min[i]), 0.0, 1e-9);
    EXPECT_NEAR(pot_scale(i, d.pot_max[i]), 4095.0, 1e-9);
    EXPECT_NEAR(pot_to_angle(i, pot_scale(i, q0(i))), q0(i), 1e-12);
    EXPECT_NEAR(pot_to_angle(i, 0), d.pot_min[i], 1e-12);
    EXPECT_NEAR(pot_to_angle(i, 4095), d.pot_max[i], 1e-12);
  }
  // Noise-free: the code is the rounded scale, within half a code's angle of the joint's.
  osc::test::RandomStates rs;
  PlantHal quiet(plant, q0);
  for (int k = 0; k < 2000; ++k) {
    const Vec6 q = rs.q_nonsingular();
    plant.reset(q);
    std::uint16_t c[6];
    quiet.read_pots(c);
    for (int i = 0; i < 6; ++i) {
      ASSERT_EQ(c[i], std::lround(pot_scale(i, q(i))));
      ASSERT_LE(std::abs(pot_to_angle(i, c[i]) - q(i)), 0.5 * (d.pot_max[i] - d.pot_min[i]) / 4095 + 1e-12);
    }
  }
  // Clamped at 0 and at full scale: beyond the span (with the noise), and by a large offset.
  Vec6 below, above;
  for (int i = 0; i < 6; ++i) {
    below(i) = d.pot_min[i] - 0.05;
    above(i) = d.pot_max[i] + 0.05;
  }
  for (const bool high : {false, true}) {
    plant.reset(high ? above : below);
    for (int k = 0; k < 100; ++k) {
      std::uint16_t c[6];
      hal.read_pots(c);
      for (int i = 0; i < 6; ++i) ASSERT_EQ(c[i], high ? 4095 : 0) << i;
    }
  }
  SensorConfig big;
  for (int i = 0; i < 6; ++i) big.pot_offset[i] = i % 2 ? 5000 : -5000;
  plant.reset(q0);
  PlantHal offset_hal(plant, q0, big);
  std::uint16_t c[6];
  offset_hal.read_pots(c);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(c[i], i % 2 ? 4095 : 0);
}

/// Turns joint j of the plant through `revs` motor revolutions (signed) in steps of 1/50 of one, a
/// sample each, from the plant's pose; collects the latched index counts.
void turn(Plant& plant, PlantHal& hal, int j, int revs, std::vector<std::int32_t>& latched) {
  constexpr int kStepsPerRev = 50;
  Vec6 q = plant.q();
  const double step = (revs > 0 ? 1 : -1) * motor_rev(j) / kStepsPerRev;
  for (int k = 0; k < std::abs(revs) * kStepsPerRev; ++k) {
    q(j) += step;
    plant.reset(q);
    std::int32_t counts[6], c;
    hal.read_encoders(counts);
    for (int i = 0; i < 6; ++i)
      if (hal.take_index(i, c)) {
        EXPECT_EQ(i, j) << "an index pulse on channel " << i << " while joint " << j << " turned";
        latched.push_back(c);
      }
  }
}

TEST(PlantSensors, IndexPulsesOncePerMotorRevolutionLatchedAtTheIndex) {
  constexpr int kRevs = 5;
  const Vec6 q0 = q_start();
  double worst_period = 0, worst_at_index = 0;
  for (const osc::EncoderMap& map : {osc::robot::kEncodersUniform, osc::robot::kDriveTrain.encoders}) {
    SensorConfig s;
    s.encoders = map;
    for (int j = 0; j < 6; ++j) {
      Plant plant;
      plant.reset(q0);
      PlantHal hal(plant, q0, s);
      std::int32_t counts[6], c;
      hal.read_encoders(counts);  // the first sample
      std::vector<std::int32_t> up, down;
      turn(plant, hal, j, kRevs, up);
      EXPECT_EQ(hal.index_pulses(j), kRevs) << map.name << " J" << j + 1;
      turn(plant, hal, j, -kRevs, down);
      EXPECT_EQ(hal.index_pulses(j), 2 * kRevs) << map.name << " J" << j + 1;
      for (int i = 0; i < 6; ++i)
        if (i != j) {
          EXPECT_EQ(hal.index_pulses(i), 0) << map.name << " J" << j + 1 << " channel " << i;
        }
      EXPECT_FALSE(hal.take_index(j, c));  // taken once
      ASSERT_EQ(up.size(), static_cast<size_t>(kRevs));
      ASSERT_EQ(down.size(), static_cast<size_t>(kRevs));
      // Back through the same index positions: the same counts, in reverse order.
      for (int k = 0; k < kRevs; ++k) EXPECT_LE(std::abs(up[k] - down[kRevs - 1 - k]), 1);
      // One motor revolution between consecutive latches.
      const double cpr = map.counts_per_rad[j], per_rev = 2 * osc::kPi * cpr / std::abs(gear(j));
      for (const auto* v : {&up, &down})
        for (int k = 1; k < kRevs; ++k)
          worst_period = std::max(worst_period, std::abs(std::abs((*v)[k] - (*v)[k - 1]) - per_rev));
      // Each latch at an index angle: the count the encoder reads there (floor), within one.
      const double e0 = hal.motor_start()(j), a = osc::robot::kDriveTrain.index_angle[j];
      for (const auto* v : {&up, &down})
        for (const std::int32_t n : *v) {
          const double theta = gear(j) * (e0 + n / cpr);
          const double level = a + 2 * osc::kPi * std::round((theta - a) / (2 * osc::kPi));
          const double at_index = std::floor((level / gear(j) - e0) * cpr);
          ASSERT_LE(std::abs(n - at_index), 1.0) << map.name << " J" << j + 1;
          worst_at_index = std::max(worst_at_index, std::abs(n - at_index));
        }
    }
  }
  std::printf(
      "index pulses: %d per %d motor revolutions each way on every channel, none elsewhere; consecutive latches one "
      "revolution apart within %.4f counts; latches within %.0f count of the count at the index\n",
      kRevs, kRevs, worst_period, worst_at_index);
  // The interpolated latch lies within (-1.5, 0.5] counts of the exact position: two latches
  // within 2 counts of a revolution apart (analytic bound).
  EXPECT_LT(worst_period, 2.0);
}

TEST(PlantSensors, IndexPulsesOfACoupledWristCountEachMotorsTurns) {
  // A coupled plant's motors (C^-1 q): turning J5 through ten of its motor's revolutions turns
  // motor 6 too (e6 gains 0.180556 e5). Each channel's detector counts its own motor's index
  // crossings, as computed from the motion's end points.
  const osc::EncoderMap& map = osc::robot::kDriveTrain.encoders;
  const EncoderCoupling C(map);
  const Vec6 q0 = q_start(), e0 = C.motor_from_joint(q0);
  IndexPulse index[6];
  for (int i = 0; i < 6; ++i) index[i] = IndexPulse(osc::robot::kDriveTrain.index_angle[i]);
  auto sample = [&](const Vec6& q) {
    const Vec6 e = C.motor_from_joint(q);
    for (int i = 0; i < 6; ++i) index[i].sample(gear(i) * e(i), encoder_count(e(i), e0(i), map.counts_per_rad[i]));
  };
  auto turns = [&](int i, const Vec6& q) {
    return std::floor((gear(i) * C.motor_from_joint(q)(i) - osc::robot::kDriveTrain.index_angle[i]) / (2 * osc::kPi));
  };
  Vec6 q = q0;
  sample(q);
  const int kSteps = 500;
  for (int k = 0; k < kSteps; ++k) {
    q(4) += 10 * motor_rev(4) / kSteps;
    sample(q);
  }
  long long expected[6];
  for (int i = 0; i < 6; ++i) expected[i] = static_cast<long long>(std::abs(turns(i, q) - turns(i, q0)));
  std::printf("coupled wrist, J5 through 10 motor revolutions: pulses");
  for (int i = 0; i < 6; ++i) std::printf(" %lld (expected %lld)", index[i].pulses(), expected[i]);
  std::printf("\n");
  for (int i = 0; i < 6; ++i) EXPECT_EQ(index[i].pulses(), expected[i]) << i;
  EXPECT_EQ(expected[4], 10);
  EXPECT_GE(expected[5], 1);  // motor 6 turned 0.18 * 76.7 / 71.9 * 10 = 1.9 revolutions
  for (int i = 0; i < 4; ++i) EXPECT_EQ(expected[i], 0);
}

TEST(PlantSensors, InjectedEncoderFaultsStayOnTheirChannel) {
  // A coupled map: a stuck channel freezes alone; a jump is ten plausible steps of the coupled
  // channel (its motor turns with the joints before it too).
  SensorConfig s;
  s.encoders = osc::robot::kDriveTrain.encoders;
  const Vec6 q0 = q_start();
  PlantConfig pc;
  pc.coupling = true;  // the motors turn as C^-1 q: what the coupled map reads
  Plant plant(pc);
  plant.reset(q0);
  Injection stuck;
  stuck.enabled = true;
  stuck.kind = InjectionKind::kEncoderStuck;
  stuck.joint = 2;
  PlantHal hal(plant, q0, s, stuck), clean(plant, q0, s);
  std::int32_t a[6], b[6];
  hal.begin_sample(0);
  hal.read_encoders(a);
  Vec6 q = q0;
  q.array() += 0.01;
  plant.reset(q);
  hal.begin_sample(0.001);
  hal.read_encoders(a);
  clean.read_encoders(b);
  for (int i = 0; i < 6; ++i) {
    if (i == 2)
      EXPECT_EQ(a[i], 0);
    else
      EXPECT_EQ(a[i], b[i]) << i;
  }
  Injection jump = stuck;
  jump.kind = InjectionKind::kEncoderJump;
  jump.joint = 5;
  PlantHal jumped(plant, q0, s, jump);
  jumped.begin_sample(0);
  jumped.read_encoders(a);
  const osc::IoMap<double> io = osc::IoMap<double>::of(s.encoders);
  const double step6 = osc::counts_per_tick_at_max_speed(5, s.encoders.counts_per_rad[5], io.inverse);
  EXPECT_GT(step6, osc::counts_per_tick_at_max_speed(5, s.encoders.counts_per_rad[5]));
  for (int i = 0; i < 6; ++i) EXPECT_EQ(a[i] - b[i], i == 5 ? static_cast<std::int32_t>(std::ceil(10 * step6)) : 0);
}

}  // namespace
