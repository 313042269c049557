// The command protocol's C++ client (host_sim/client/osc_client.hpp) against the controller's own
// end of the protocol (CommandPort over the simulated arm, MotionSim) through an in-process
// transport that runs the simulator's ticks while the client waits: what the answers mean (done,
// aborted with a reason, refused), the state frames, the texts with the firmware's names; and the
// serial transport's named errors, any baud rate and a hang-up on a pseudo-terminal.
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>

#include "motion_sim.hpp"
#include "osc/link/command_port.hpp"
#include "osc_client.hpp"

namespace {

using osc::client::Client;
using osc::client::Outcome;
using osc::client::Status;

/// The controller on the other end: a read runs ticks (1 ms each) until bytes are there or the
/// timeout has passed in simulated time; a write goes through the port at once, as bytes arriving
/// between two ticks.
class SimTransport : public osc::client::Transport {
 public:
  SimTransport() : sim_(sim::Vec6(osc::joint_vector<double>(osc::robot::kQStart))) {}
  int read(std::uint8_t* buf, int n, double timeout_s) override {
    if (broken) return error_ = "loopback: broken", -1;
    const long ticks = std::max(1L, std::lround(timeout_s * osc::params::kControlHz));
    for (long k = 0; out_.empty() && k < ticks; ++k) tick();
    const int m = std::min(n, static_cast<int>(out_.size()));
    std::copy_n(out_.begin(), m, buf);
    out_.erase(out_.begin(), out_.begin() + m);
    return m;
  }
  bool write(const std::uint8_t* b, int n) override {
    for (int i = 0; i < n; ++i)
      if (in_.feed(b[i]) == pil::Parser::kFrame) port_.on_frame(sim_.task(), in_, emit());
    return true;
  }
  void tick() {
    sim_.tick();
    port_.after_tick_and_poll(sim_.task(), emit());
  }
  sim::MotionSim<double>& sim() { return sim_; }
  bool broken = false;

 private:
  std::function<void(const std::uint8_t*, int)> emit() {
    return [this](const std::uint8_t* b, int n) { out_.insert(out_.end(), b, b + n); };
  }
  sim::MotionSim<double> sim_;
  osc::CommandPort<double> port_;
  pil::Parser in_;
  std::deque<std::uint8_t> out_;
};

struct OscClient : ::testing::Test {
  SimTransport* t = new SimTransport;
  Client c{std::unique_ptr<osc::client::Transport>(t)};

  static osc::MoveRequest<double> relative(double dx, double dy, double dz, double v = 0) {
    osc::MoveRequest<double> m;
    m.position = osc::Vec3<double>(dx, dy, dz);
    m.relative = true;
    if (v > 0) {
      m.has_limits = true;
      m.limits = osc::CartesianLimits<double>::defaults();
      m.limits.linear.v = v;
    }
    return m;
  }
  void enable() {
    const Outcome o = c.wait_answer(c.enable(), 10);
    ASSERT_EQ(o.status, Status::kAccepted) << o.text();
  }
  /// Every command of ids ended exactly once in the answers the client received (osc::answer_ends:
  /// done, or aborted with a reason).
  void expect_each_ended_once(const std::vector<std::uint32_t>& ids) const {
    for (std::uint32_t id : ids)
      EXPECT_EQ(std::count_if(answers.begin(), answers.end(),
                              [id](const pil::AnswerFrame& a) { return osc::answer_ends(a, id); }),
                1)
          << "command " << id;
  }
  /// Every answer frame received.
  std::vector<pil::AnswerFrame> answers;
  void SetUp() override {
    c.on_answer = [this](const pil::AnswerFrame& a) { answers.push_back(a); };
  }
};

TEST_F(OscClient, RefusedWhileDisabledThenEnabledAndAMoveDone) {
  auto s = c.state(1);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->state, static_cast<std::uint8_t>(osc::MotionState::kDisabled));
  const std::uint32_t refused = c.move_to(relative(0, 0.02, 0));
  EXPECT_NE(refused, 0u);
  const Outcome r = c.wait_done(refused, 10);
  EXPECT_EQ(r.status, Status::kRefused);
  EXPECT_EQ(r.reason, osc::MotionReason::kNotEnabled);
  EXPECT_EQ(r.text(), "refused: not_enabled");
  enable();
  const float y0 = c.state(1)->x_d[1];
  const std::uint32_t id = c.move_to(relative(0, 0.02, 0));
  EXPECT_EQ(c.wait_answer(id, 10).status, Status::kAccepted);
  const Outcome d = c.wait_done(id, 60);
  EXPECT_EQ(d.status, Status::kDone) << d.text();
  EXPECT_EQ(d.answer.done_id, id);
  s = c.state(1);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->state, static_cast<std::uint8_t>(osc::MotionState::kHolding));
  EXPECT_NEAR(s->x_d[1] - y0, 0.02, 1e-6);
  EXPECT_NEAR(s->x[1] - y0, 0.02, 1e-3);  // the simulated arm followed
}

/// A gain set over the link (torque off) takes effect on the next move: softer gains (69) track the
/// same move worse, from the state frames (reference minus measured pose); a set while enabled is
/// refused torque_on and changes nothing. A first move teaches the momentum law (the default) the
/// friction, which it identifies within one move (the first move's error, 1.4 mm, is mostly that),
/// so that both compared moves run with it learned.
TEST_F(OscClient, AGainSetOverTheLinkTakesEffectOnTheNextMove) {
  const auto move_error = [this] {
    double worst = 0;
    c.on_state = [&worst](const pil::StateFrame& s) {
      for (int i = 0; i < 3; ++i) worst = std::max(worst, std::fabs(static_cast<double>(s.x_d[i] - s.x[i])));
    };
    enable();
    const Outcome d = c.wait_done(c.move_to(relative(0, 0.03, 0, 0.1)), 60);
    EXPECT_EQ(d.status, Status::kDone) << d.text();
    c.on_state = nullptr;
    EXPECT_EQ(c.wait_done(c.disable(), 10).status, Status::kDone);
    return worst;
  };
  const double first = move_error();
  const double stiff = move_error();
  std::printf("first move (friction not yet learned) %.3g m\n", first);
  const int ks = osc::param_index("ks"), ki = osc::param_index("ki");
  for (int e = 0; e < 3; ++e) {
    auto a = c.param(pil::kParamOpSet, ks, e, 10);
    ASSERT_TRUE(a) << c.error();
    EXPECT_EQ(a->status, static_cast<std::uint8_t>(osc::ParamStatus::kOk));
    a = c.param(pil::kParamOpSet, ki, e, 100);
    ASSERT_TRUE(a) << c.error();
    EXPECT_EQ(a->status, static_cast<std::uint8_t>(osc::ParamStatus::kOk));
  }
  EXPECT_EQ(t->sim().task().gains.ki(1), 100);
  const double soft = move_error();
  std::printf("move error: paper gains %.3g m, softer %.3g m\n", stiff, soft);
  EXPECT_GT(soft, 2.5 * stiff) << "paper gains " << stiff << " m, softer " << soft << " m";
  enable();
  const auto refused = c.param(pil::kParamOpSet, ki, 0, 2000);
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, static_cast<std::uint8_t>(osc::ParamStatus::kTorqueOn));
  EXPECT_EQ(refused->value, 100.0f);
}

TEST_F(OscClient, AStopAbortsTheRunningMoveAndDropsEveryMoveQueuedBehindIt) {
  enable();
  // A full queue: the running move and sixteen waiting, each sent once the one before was answered.
  std::vector<std::uint32_t> ids;
  for (int k = 0; k <= osc::params::kMoveQueueLength; ++k) {
    ids.push_back(c.move_to(relative(0, k % 2 ? -0.002 : 0.002, 0, 0.01)));
    ASSERT_EQ(c.wait_answer(ids.back(), 10).status, Status::kAccepted) << k;
  }
  const Outcome full = c.wait_answer(c.move_to(relative(0, 0.002, 0)), 10);
  EXPECT_EQ(full.text(), "refused: queue_full");
  EXPECT_EQ(c.state(1)->queued, ids.size());
  const std::uint32_t stop = c.stop();
  const Outcome s = c.wait_answer(stop, 10);
  ASSERT_EQ(s.status, Status::kAccepted);
  EXPECT_EQ(s.answer.aborted_id, ids[0]);
  for (std::uint32_t id : ids) {
    const Outcome o = c.wait_done(id, 10);
    EXPECT_EQ(o.status, Status::kAborted) << id;
    EXPECT_EQ(o.answer.aborted_id, id);
    EXPECT_EQ(o.text(), id == ids[0] ? "aborted: stop_command" : "aborted: dropped");
  }
  const Outcome rest = c.wait_done(stop, 30);  // a stop is done at rest
  EXPECT_EQ(rest.status, Status::kDone);
  EXPECT_EQ(rest.answer.completion, static_cast<std::uint8_t>(osc::MotionCompletion::kStopped));
  expect_each_ended_once(ids);
  const auto st = c.state(1);
  ASSERT_TRUE(st);
  EXPECT_EQ(st->state, static_cast<std::uint8_t>(osc::MotionState::kHolding));
  EXPECT_EQ(st->queued, 0);
  EXPECT_EQ(st->running_id, 0u);
}

/// A re-target drops the moves waiting; a second one while the first brakes drops the first's
/// move (the braking motion was aborted already) and starts from where the braking motion comes
/// to rest.
TEST_F(OscClient, AReplaceDropsTheQueueAndASecondReplaceDuringItsBrakeTheFirstsMove) {
  enable();
  const auto s0 = c.state(1);
  ASSERT_TRUE(s0);
  const std::uint32_t a = c.move_to(relative(0, 0.02, 0, 0.01));
  ASSERT_EQ(c.wait_answer(a, 10).status, Status::kAccepted);
  const std::uint32_t b = c.move_to(relative(0, -0.02, 0));
  ASSERT_EQ(c.wait_answer(b, 10).status, Status::kAccepted);
  osc::MoveRequest<double> r = relative(0.02, 0, 0);
  r.replace = true;
  const std::uint32_t d = c.move_to(r);
  const Outcome od = c.wait_answer(d, 10);
  ASSERT_EQ(od.status, Status::kAccepted);
  EXPECT_EQ(od.answer.aborted_id, a);
  EXPECT_EQ(od.answer.abort, static_cast<std::uint8_t>(osc::MotionReason::kSuperseded));
  r = relative(0, 0, 0.01);
  r.replace = true;
  const std::uint32_t e = c.move_to(r);
  const Outcome oe = c.wait_answer(e, 10);
  ASSERT_EQ(oe.status, Status::kAccepted);
  EXPECT_EQ(oe.answer.aborted_id, 0u);  // the braking move was aborted already
  EXPECT_EQ(c.wait_done(a, 1).text(), "aborted: superseded");
  EXPECT_EQ(c.wait_done(b, 1).text(), "aborted: dropped");
  EXPECT_EQ(c.wait_done(d, 1).text(), "aborted: dropped");
  const Outcome done = c.wait_done(e, 60);
  EXPECT_EQ(done.status, Status::kDone) << done.text();
  expect_each_ended_once({a, b, d, e});
  // e went 10 mm up from where a came to rest (a barely started along y: 10 mm/s for a few ticks),
  // not from where d would have ended (20 mm along x).
  const auto st = c.state(1);
  ASSERT_TRUE(st);
  EXPECT_NEAR(st->x_d[0] - s0->x_d[0], 0, 1e-4);
  EXPECT_NEAR(st->x_d[1] - s0->x_d[1], 0, 1e-3);
  EXPECT_NEAR(st->x_d[2] - s0->x_d[2], 0.01, 1e-4);
  EXPECT_EQ(st->queued, 0);
}

TEST_F(OscClient, AFaultAbortsTheMoveAndDropsTheQueueAndTheStateFrameSaysSoUntilTheNextEnable) {
  enable();
  std::vector<std::uint32_t> ids;
  for (int k = 0; k < 4; ++k) {
    ids.push_back(c.move_to(relative(0, k % 2 ? -0.01 : 0.01, 0)));
    ASSERT_EQ(c.wait_answer(ids.back(), 10).status, Status::kAccepted) << k;
  }
  t->sim().task().inject_nonfinite();  // the next tick's step is not finite: a fault
  for (std::uint32_t id : ids) {
    const Outcome o = c.wait_done(id, 1);
    EXPECT_EQ(o.text(), id == ids[0] ? "aborted: faulted" : "aborted: dropped") << id;
    EXPECT_EQ(o.answer.state, static_cast<std::uint8_t>(osc::MotionState::kFault));
    EXPECT_EQ(o.answer.queued, 0);
  }
  expect_each_ended_once(ids);
  const auto expect_nothing_queued = [this](osc::MotionState state) {
    const auto st = c.state(1);
    ASSERT_TRUE(st);
    EXPECT_EQ(st->state, static_cast<std::uint8_t>(state));
    EXPECT_EQ(st->queued, 0);
    EXPECT_EQ(st->running_id, 0u);
  };
  expect_nothing_queued(osc::MotionState::kFault);
  EXPECT_EQ(c.wait_answer(c.clear(), 10).status, Status::kAccepted);
  expect_nothing_queued(osc::MotionState::kDisabled);
}

TEST_F(OscClient, StateIsAFreshFrameAndAnswersReachTheHandler) {
  const std::uint32_t t0 = c.state(1)->tick;
  const std::uint32_t t1 = c.state(1)->tick;
  EXPECT_GT(t1, t0);
  std::vector<pil::AnswerFrame> seen;
  c.on_answer = [&](const pil::AnswerFrame& a) { seen.push_back(a); };
  const std::uint32_t id = c.enable();
  ASSERT_TRUE(c.pump(0.5));
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].id, id);
  const std::string text = osc::client::answer_text(seen[0]);
  EXPECT_NE(text.find("enable " + std::to_string(id) + " accepted; state holding"), std::string::npos) << text;
}

TEST_F(OscClient, ATransportErrorIsNamed) {
  t->broken = true;
  const Outcome o = c.wait_answer(c.enable(), 1);
  EXPECT_EQ(o.status, Status::kError);
  EXPECT_EQ(o.text(), "error: loopback: broken");
  EXPECT_FALSE(c.state(1));
  EXPECT_EQ(c.error(), "loopback: broken");
}

TEST(OscClientText, NamesAreTheFirmwares) {
  EXPECT_EQ(osc::client::fault_names(0), "none");
  EXPECT_EQ(osc::client::fault_names(osc::kFaultTracking | osc::kFaultEstop | (1u << 31)), "tracking,estop,bit31");
  pil::StateFrame s;
  s.state = static_cast<std::uint8_t>(osc::MotionState::kStopping);
  s.stop = static_cast<std::uint8_t>(osc::StopCategory::kCategory2);
  const std::string text = osc::client::state_text(s);
  EXPECT_NE(text.find("state: stopping\nstop: category_2\nfaults: none\n"), std::string::npos) << text;
  // The saved friction's check (issue 57): J1 and J2 checked, J2 stale, the others not yet.
  s.friction_checked = 0x3, s.friction_stale = 0x2;
  EXPECT_NE(osc::client::state_text(s).find("friction_fit: J1 fits, J2 stale, J3 -, J4 -, J5 -, J6 -\n"),
            std::string::npos);
  pil::AnswerFrame a;
  a.id = 9, a.verb = static_cast<std::uint8_t>(osc::MotionVerb::kMoveTo);
  a.outcome = static_cast<std::uint8_t>(osc::CommandOutcome::kRefused);
  a.refusal = static_cast<std::uint8_t>(osc::MotionReason::kOutOfWorkspace);
  EXPECT_EQ(osc::client::answer_text(a), "tick 0: move_to 9 refused: out_of_workspace; state disabled, queued 0");
}

TEST(OscClientPath, ResampledLinearlyWithTheLastSampleAtTheEnd) {
  const std::vector<std::array<double, 7>> rows = {{0, 0, 0, 0, 0, 0, 0}, {0.25, 0.1, 0, 0, 0, 0, 0.2}};
  const auto p = osc::client::resample_path(rows, 10);
  ASSERT_EQ(p.size(), 4u);  // 0, 0.1, 0.2, then the end (0.25) instead of 0.3
  EXPECT_NEAR(p[1].position(0), 0.04, 1e-12);
  EXPECT_NEAR(p[2].rpy(2), 0.16, 1e-12);
  EXPECT_EQ(p[3].position(0), 0.1);
  EXPECT_EQ(osc::client::resample_path({{0, 1, 2, 3, 0, 0, 0}}, 50).size(), 1u);  // one row: one sample
}

// The velocity of each sample: the segment's slope, its angular part the angular velocity of
// R(rpy(t)) = Rz Ry Rx (checked against differences of R itself: w^ = R_dot R^T); zero at the end.
TEST(OscClientPath, EachSampleCarriesThePathsVelocity) {
  const std::vector<std::array<double, 7>> rows = {{0, 0, 0, 0, 0.1, 0.2, 0.3},
                                                   {0.5, 0.05, -0.02, 0.01, 0.3, -0.1, 0.6}};
  const auto p = osc::client::resample_path(rows, 10);
  ASSERT_EQ(p.size(), 6u);
  const auto R = [](const osc::Vec3<double>& a) {
    return osc::Mat3<double>(Eigen::AngleAxisd(a(2), osc::Vec3<double>::UnitZ()) *
                             Eigen::AngleAxisd(a(1), osc::Vec3<double>::UnitY()) *
                             Eigen::AngleAxisd(a(0), osc::Vec3<double>::UnitX()));
  };
  for (std::size_t k = 0; k + 1 < p.size(); ++k) {
    EXPECT_NEAR(p[k].velocity(0), 0.1, 1e-12);
    EXPECT_NEAR(p[k].velocity(1), -0.04, 1e-12);
    EXPECT_NEAR(p[k].velocity(2), 0.02, 1e-12);
    const osc::Vec3<double> rate(0.4, -0.6, 0.6), a = p[k].rpy;
    const double h = 1e-6;
    const osc::Mat3<double> W = (R(a + h * rate) - R(a - h * rate)) / (2 * h) * R(a).transpose();
    EXPECT_LE((p[k].velocity.tail<3>() - osc::Vec3<double>(W(2, 1), W(0, 2), W(1, 0))).norm(), 1e-8) << k;
  }
  EXPECT_EQ(p.back().velocity.norm(), 0.0);
}

TEST(SerialTransport, BadPathsAreNamed) {
  std::string err;
  EXPECT_FALSE(osc::client::SerialTransport::open("/nonexistent/tty", 115200, err));
  EXPECT_EQ(err, "/nonexistent/tty: No such file or directory");
  EXPECT_FALSE(osc::client::SerialTransport::open("/dev/null", 115200, err));
  EXPECT_EQ(err, "/dev/null: not a serial device or terminal");
  EXPECT_FALSE(osc::client::SerialTransport::open("/dev/null", 7, err));
  EXPECT_EQ(err, "baud 7: 50 to 4000000");
}

TEST(SerialTransport, AnyBaudOnAPseudoTerminalAndAHangUpIsNamed) {
  const int m = posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(m, 0);
  ASSERT_EQ(grantpt(m), 0);
  ASSERT_EQ(unlockpt(m), 0);
  const std::string slave = ptsname(m);
  std::string err;
  for (int baud : {115200, 123457}) {  // a standard rate, and one only termios2 sets
    auto t = osc::client::SerialTransport::open(slave, baud, err);
    ASSERT_TRUE(t) << err;
    const std::uint8_t hello[3] = {1, 2, 3};
    ASSERT_TRUE(t->write(hello, 3));
    std::uint8_t got[8];
    ASSERT_EQ(::read(m, got, sizeof got), 3);  // raw: no echo, no translation
    EXPECT_EQ(got[2], 3);
    EXPECT_EQ(::write(m, hello, 2), 2);
    EXPECT_EQ(t->read(got, sizeof got, 1.0), 2);
    EXPECT_EQ(t->read(got, sizeof got, 0.01), 0);  // nothing more: a timeout
  }
  auto t = osc::client::SerialTransport::open(slave, 115200, err);
  ASSERT_TRUE(t);
  close(m);
  std::uint8_t got[8];
  EXPECT_EQ(t->read(got, sizeof got, 1.0), -1);
  EXPECT_EQ(t->error(), slave + ": hung up (the board or the simulator has gone)");
}

}  // namespace
