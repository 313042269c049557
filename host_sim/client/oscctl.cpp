// oscctl: commands a controller over the command protocol (docs/motion.md, "Clients"), on a serial
// device or the simulator's pseudo-terminal (osc_sim --pty):
//
//   oscctl --port /dev/pts/7 state | enable | disable | clear | paper | stop | home | identify [--apply]
//   oscctl --port /dev/pts/7 move X Y Z [--rpy R P Y] [--relative] [--v V --a A --j J] [--replace] [--no-wait]
//   oscctl --port /dev/pts/7 stream FILE.csv --rate HZ [--velocity] [--relative] [--v V --a A --j J]
//   oscctl --port /dev/pts/7 watch [--seconds S]
//   oscctl --port /dev/pts/7 param list | get NAME | set NAME VALUE... [--element E] | save | load | reset | check
//
// Each command prints its outcome, one line each: "accepted" or "refused: REASON"; then, for a move,
// a stream, a stop or a disable it waits for, "done" or "aborted: REASON" (a stop prints the motion it
// aborted first: "aborted ID: stop_command"). Exit status 0 when accepted or done, 1 when refused,
// aborted or timed out, 2 for a bad command line, port or file.
#include <signal.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_parse.hpp"
#include "motion_script.hpp"
#include "osc_client.hpp"

namespace {

using osc::client::Client;
using osc::client::Outcome;
using osc::client::Status;

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_signal(int) { g_stop = 1; }

struct Args {
  std::string port, verb, csv, pose;
  int baud = 115200;
  double timeout = 120;
  double keepalive = Client::kKeepAliveDefault;
  std::vector<double> xyz, rpy;
  bool relative = false, replace = false, no_wait = false, velocity = false;
  double v = 0, a = 0, j = 0, rate = 0, seconds = 0;
  std::vector<std::array<double, 7>> rows;  // stream: the path
  bool has_rpy = false;
  std::string param_op, param_name;  // param: the operation, the parameter's name
  std::vector<double> param_values;
  int element = -1;
  bool apply = false;    // identify: the estimate into the parameters
  bool payload = false;  // identify: the payload's estimate too (the flag payload)
};

constexpr double kDeg = osc::kPi / 180.0;
/// How long identify waits for the estimate after the run's end [s] (the Python client's IDENTIFY_FRAME_WAIT): the
/// board solves it after the end and sends it at once. The solve is 27 million instructions (0.2 s on the F407,
/// seconds on a slow core), and a simulator on a loaded machine falls behind; the wait ends when the frame comes.
/// 2 s was not enough on a loaded machine once (virtual_board_oscctl_payload under the host tests at -j4).
constexpr double kIdentifyFrameWaitS = 10.0;

int exit_of(const Outcome& o) { return o.ok() ? 0 : o.status == Status::kError ? 2 : 1; }

/// Prints an outcome; its exit status.
int report(const Outcome& o) {
  std::printf("%s\n", o.text().c_str());
  std::fflush(stdout);
  return exit_of(o);
}

/// The limits of --v --a --j over the configured maxima (those not given keep theirs).
bool limits_of(const Args& a, osc::MoveRequest<double>& m) {
  m.limits = osc::CartesianLimits<double>::defaults();
  if (a.v > 0) m.limits.linear.v = a.v, m.has_limits = true;
  if (a.a > 0) m.limits.linear.a = a.a, m.has_limits = true;
  if (a.j > 0) m.limits.linear.j = a.j, m.has_limits = true;
  return m.has_limits;
}

/// A command without arguments: its answer; a stop or a disable also its end (at rest).
int simple(Client& c, const Args& a, osc::MotionVerb verb) {
  const std::uint32_t id = c.command(verb);
  if (id == 0) return report({Status::kError, 0, osc::MotionReason::kNone, 0, c.error(), {}});
  const Outcome o = c.wait_answer(id, a.timeout);
  const int rc = report(o);
  if (o.status != Status::kAccepted) return rc;
  if (o.answer.abort != 0)
    std::printf("aborted %u: %s\n", o.answer.aborted_id,
                osc::motion_name(static_cast<osc::MotionReason>(o.answer.abort)));
  if (verb != osc::MotionVerb::kStop && verb != osc::MotionVerb::kDisable && verb != osc::MotionVerb::kHome &&
      verb != osc::MotionVerb::kIdentify)
    return rc;
  return report(c.wait_done(id, a.timeout));
}

/// declare_pose NAME: the pose's code in the frame's period field (the protocol's).
int declare_pose(Client& c, const Args& a) {
  osc::MoveRequest<double> m;
  m.period = static_cast<std::uint32_t>(osc::robot::named_pose_code(a.pose));  // checked by the parser
  const std::uint32_t id = c.command(osc::MotionVerb::kDeclarePose, m);
  if (id == 0) return report({Status::kError, 0, osc::MotionReason::kNone, 0, c.error(), {}});
  return report(c.wait_answer(id, a.timeout));
}

int move(Client& c, const Args& a) {
  osc::MoveRequest<double> m;
  m.position = osc::Vec3<double>(a.xyz[0], a.xyz[1], a.xyz[2]);
  if (!a.rpy.empty()) m.rpy = osc::Vec3<double>(a.rpy[0], a.rpy[1], a.rpy[2]) * kDeg, m.has_rpy = true;
  m.relative = a.relative;
  m.replace = a.replace;
  limits_of(a, m);
  const std::uint32_t id = c.move_to(m);
  if (id == 0) return report({Status::kError, 0, osc::MotionReason::kNone, 0, c.error(), {}});
  const Outcome o = c.wait_answer(id, a.timeout);
  std::printf("%s (id %u)\n", o.text().c_str(), id);
  std::fflush(stdout);
  if (o.status != Status::kAccepted || a.no_wait) return exit_of(o);
  return report(c.wait_done(id, a.timeout));
}

int stream(Client& c, const Args& a) {
  osc::MoveRequest<double> m;
  const bool lim = limits_of(a, m);
  const Outcome o = c.stream(osc::client::resample_path(a.rows, a.rate), a.has_rpy, a.rate, a.relative,
                             lim ? &m.limits : nullptr, a.timeout, a.velocity);
  if (o.status == Status::kError) {
    std::fprintf(stderr, "oscctl: %s\n", o.error.c_str());
    return 2;
  }
  std::printf("%s (id %u)\n", o.status == Status::kAccepted ? "accepted" : o.text().c_str(), o.id);
  std::fflush(stdout);
  if (o.skipped > 0)
    std::fprintf(stderr, "oscctl: warning: %u setpoints skipped: this client fell behind the stream's schedule\n",
                 o.skipped);
  if (o.status != Status::kAccepted) return exit_of(o);
  return report(c.wait_done(o.id, a.timeout));
}

/// A stream's file and rate, checked before the port is opened.
bool check_stream(Args& a, std::string& err) {
  if (!sim::read_stream_csv(a.csv, a.rows, a.has_rpy, err)) return false;
  const double period = 1000.0 / a.rate;
  if (std::fabs(period - std::round(period)) > 1e-9) {
    char buf[120];
    std::snprintf(buf, sizeof buf, "--rate %g: not 1000 / N Hz for a whole N (1000, 500, 250, 100, 50, 20, 10 ...)",
                  a.rate);
    return err = buf, false;
  }
  return true;
}

int state(Client& c, const Args& a) {
  const auto s = c.state(std::min(a.timeout, 10.0));
  if (!s) {
    std::fprintf(
        stderr, "oscctl: %s\n",
        c.error().empty() ? "no state frame within the time (is a controller on the port?)" : c.error().c_str());
    return c.error().empty() ? 1 : 2;
  }
  std::printf("%s", osc::client::state_text(*s).c_str());
  return 0;
}

/// Prints every answer and every change of the state frame's state, stop, faults, queue or running id.
int watch(Client& c, const Args& a) {
  pil::StateFrame last{};
  bool first = true;
  c.on_answer = [](const pil::AnswerFrame& f) {
    std::printf("%s\n", osc::client::answer_text(f).c_str());
    std::fflush(stdout);
  };
  c.on_state = [&](const pil::StateFrame& s) {
    if (!first && s.state == last.state && s.stop == last.stop && s.faults == last.faults && s.queued == last.queued &&
        s.running_id == last.running_id)
      return;
    std::printf("tick %u: state %s, stop %s, faults %s, queued %u, running_id %u\n", s.tick,
                osc::motion_name(static_cast<osc::MotionState>(s.state)),
                osc::motion_name(static_cast<osc::StopCategory>(s.stop)), osc::client::fault_names(s.faults).c_str(),
                s.queued, s.running_id);
    std::fflush(stdout);
    first = false;
    last = s;
  };
  for (double left = a.seconds > 0 ? a.seconds : 1e18; left > 0 && !g_stop; left -= 0.1)
    if (!c.pump(std::min(left, 0.1))) {
      std::fprintf(stderr, "oscctl: %s\n", c.error().c_str());
      return 2;
    }
  return 0;
}

/// One parameter element's line: "ks[2] = 97 (0.001 to 100000; torque_off)".
void print_param(int i, const pil::ParamAnswerFrame& r) {
  const osc::ParamInfo& p = osc::kParams[i];
  std::string idx = p.count > 1 ? "[" + std::to_string(r.element) + "]" : "";
  std::printf("%s%s = %.7g%s%s (%.7g to %.7g%s)\n", p.name, idx.c_str(), static_cast<double>(r.value),
              *p.unit ? " " : "", p.unit, static_cast<double>(r.lo), static_cast<double>(r.hi),
              (r.flags & pil::kParamFlagTorqueOff) ? "; torque_off" : "");
}

/// A param answer's status: 0 ok, 1 refused (the reason printed), 2 no answer.
int param_status(const Client& c, const std::optional<pil::ParamAnswerFrame>& r, const char* what) {
  if (!r) {
    std::fprintf(stderr, "oscctl: param %s: %s\n", what, c.error().c_str());
    return 2;
  }
  if (r->status == static_cast<std::uint8_t>(osc::ParamStatus::kOk)) return 0;
  const int s = r->status < osc::kParamStatusCount ? r->status : static_cast<int>(osc::ParamStatus::kBadOp);
  std::printf("refused: %s (%s)\n", osc::kParamStatusNames[s], osc::kParamStatusDocs[s]);
  return 1;
}

void print_margins(const pil::ParamAnswerFrame& r) {
  std::printf("observer margin %.3g (stable above 1: (4 - 2 k dt) / (b dt^2), b <= %.4g 1/s^2 at the last pose)\n",
              static_cast<double>(r.margins[0]), static_cast<double>(r.margins[1]));
  std::printf("loop margin %.3g (stable at 1 or above: the factor the gains may grow by at the last pose)\n",
              static_cast<double>(r.margins[3]));
  std::printf("condition (37) %.3g (k_s k_nd / 2: above 1 it can hold)%s\n", static_cast<double>(r.margins[2]),
              (r.flags & pil::kParamFlagWarn37) ? ": warning, the paper's sufficient condition cannot hold" : "");
}

int param(Client& c, const Args& a) {
  const auto op_of = [](const std::string& name) {
    for (int k = 0; k < pil::kParamOpCount; ++k)
      if (name == pil::kParamOpNames[k]) return static_cast<std::uint8_t>(k);
    return static_cast<std::uint8_t>(pil::kParamOpCount);
  };
  if (a.param_op == "list") {
    for (int i = 0; i < osc::kParamCount; ++i)
      for (int e = 0; e < osc::kParams[i].count; ++e) {
        const auto r = c.param(pil::kParamOpGet, i, e, 0, a.timeout);
        if (const int rc = param_status(c, r, "get")) return rc;
        print_param(i, *r);
      }
    return 0;
  }
  const int i = osc::param_index(a.param_name.c_str());
  if (a.param_op == "get" || a.param_op == "set") {
    const osc::ParamInfo& p = osc::kParams[i];
    if (a.param_op == "get") {
      for (int e = 0; e < p.count; ++e) {
        if (a.element >= 0 && e != a.element) continue;
        const auto r = c.param(pil::kParamOpGet, i, e, 0, a.timeout);
        if (const int rc = param_status(c, r, "get")) return rc;
        print_param(i, *r);
      }
      return 0;
    }
    for (std::size_t k = 0; k < a.param_values.size(); ++k) {
      const int e = a.element >= 0 ? a.element : static_cast<int>(k);
      const auto r = c.param(pil::kParamOpSet, i, e, a.param_values[k], a.timeout);
      if (const int rc = param_status(c, r, "set")) {
        if (r && r->margins[1] > 0) print_margins(*r);
        return rc;
      }
      print_param(i, *r);
      if (r->flags & pil::kParamFlagWarn37) print_margins(*r);
    }
    return 0;
  }
  const auto r = c.param(op_of(a.param_op), 0, 0, 0, a.timeout);
  if (const int rc = param_status(c, r, a.param_op.c_str())) return rc;
  if (a.param_op == "check")
    print_margins(*r);
  else
    std::printf("%s: ok\n", a.param_op.c_str());
  return 0;
}

/// An identify frame: the verdict, then per drive each coefficient with its standard deviation, `*` where it is
/// identified.
void print_identify(const pil::IdentifyFrame& f) {
  const auto status = static_cast<osc::IdentifyStatus>(f.status);
  const char* name = f.status < osc::kIdentifyStatusCount ? osc::identify_status_name(status) : "?";
  std::printf("identify %u: %s; %u samples, %u lost; condition %.3g; worst torque-prediction error %.1f %%\n", f.id,
              name, f.samples, f.lost, static_cast<double>(f.condition), 100.0 * f.prediction_error);
  if (status != osc::IdentifyStatus::kOk) return;
  std::printf("drive  %-22s %-22s %-22s %s\n", "viscous [N m s/rad]", "Coulomb [N m]", "Stribeck [N m]",
              "armature correction [kg m^2]");
  for (int i = 0; i < osc::kDof; ++i) {
    std::printf("J%d    ", i + 1);
    for (int c = 0; c < 3; ++c) {
      const int k = c * osc::kDof + i;
      std::printf(" %9.4f +- %-7.4f%s", static_cast<double>(f.friction[k]), static_cast<double>(f.friction_sd[k]),
                  (f.identified >> k) & 1u ? "* " : "  ");
    }
    std::printf(" %9.4f +- %.4f\n", static_cast<double>(f.armature[i]), static_cast<double>(f.armature_sd[i]));
  }
  std::printf("(* identified: its standard deviation within %g %% of it)\n", 100 * osc::params::kIdentifiedFraction);
}

/// An identify_offset frame: each drive's torque offset with its standard deviation, on one line (reported; no
/// parameter takes it).
void print_identify_offset(const pil::IdentifyOffsetFrame& f) {
  if (f.status != static_cast<std::uint8_t>(osc::IdentifyStatus::kOk)) return;
  std::printf("torque offset [N m] (what each drive adds to the torque commanded; reported, not applied):");
  for (int i = 0; i < osc::kDof; ++i)
    std::printf(" J%d %.4f +- %.4f", i + 1, static_cast<double>(f.offset[i]), static_cast<double>(f.offset_sd[i]));
  std::printf("\n");
}

/// An identify_payload frame: the payload's mass, centre of mass and inertia about it, then the standard deviations
/// of the estimated parameters (mass, first moment m c, inertia about frame 6's origin), `*` where identified.
void print_identify_payload(const pil::IdentifyPayloadFrame& f) {
  const auto star = [&](int k) { return (f.identified >> k) & 1u ? "*" : ""; };
  const auto d = [](float v) { return static_cast<double>(v); };
  if (f.status != static_cast<std::uint8_t>(osc::IdentifyStatus::kOk)) return;
  std::printf("payload: mass %.4f kg +- %.4f%s, centre of mass (%.2f, %.2f, %.2f) mm\n", d(f.mass), d(f.pi_sd[0]),
              star(0), 1e3 * d(f.com[0]), 1e3 * d(f.com[1]), 1e3 * d(f.com[2]));
  std::printf("  inertia about it (Ixx Iyy Izz Ixy Ixz Iyz) [kg m^2]:");
  for (float v : f.inertia) std::printf(" %.4g", d(v));
  std::printf("\n  standard deviations: m c [kg m]");
  for (int k = 1; k < 4; ++k) std::printf(" %.2g%s", d(f.pi_sd[k]), star(k));
  std::printf("; inertia about frame 6's origin (Ixx Ixy Ixz Iyy Iyz Izz) [kg m^2]");
  for (int k = 4; k < 10; ++k) std::printf(" %.2g%s", d(f.pi_sd[k]), star(k));
  std::printf("\n");
}

/// identify --payload --apply: the payload's estimate into payload_mass, payload_com and payload_inertia (the torque
/// off already). The inertia goes in zeroed first, then its moments before its products; where the parameters refuse
/// it (not_physical, or a moment below 0 out_of_range: an estimate's noise about a point mass), it is zeroed again,
/// products first, and left so, and said. A mass within two of its standard deviations of 0 is no payload (its centre
/// of mass is noise over noise): all of it set to 0. Then payload_allowance goes back to 0: the payload is identified.
int apply_identify_payload(Client& c, const Args& a, const pil::IdentifyPayloadFrame& f) {
  const auto set = [&](const char* name, int e, double v, bool quiet_refusal = false) -> int {
    const auto r = c.param(pil::kParamOpSet, osc::param_index(name), e, v, a.timeout);
    if (quiet_refusal && r &&
        (r->status == static_cast<std::uint8_t>(osc::ParamStatus::kNotPhysical) ||
         r->status == static_cast<std::uint8_t>(osc::ParamStatus::kOutOfRange)))
      return -1;
    if (const int rc = param_status(c, r, "set")) return rc;
    print_param(osc::param_index(name), *r);
    return 0;
  };
  const bool none = !(f.mass > 2 * f.pi_sd[0]);
  const double keep = none ? 0.0 : 1.0;
  int rc = set("payload_mass", 0, keep * static_cast<double>(f.mass));
  for (int k = 0; k < 3 && rc == 0; ++k) rc = set("payload_com", k, keep * static_cast<double>(f.com[k]));
  for (int k = 0; k < 6 && rc == 0; ++k) rc = set("payload_inertia", k, 0.0);
  if (none && rc == 0) std::printf("payload: none found (its mass within 2 standard deviations of 0): set to none\n");
  for (int k = 0; k < 6 && rc == 0 && !none; ++k)
    rc = set("payload_inertia", k, static_cast<double>(f.inertia[k]), true);
  if (rc == -1) {
    // Back in the reverse order: each zero returns to a tensor the board accepted on the way (a moment zeroed
    // before the products would leave a product beside a zero moment, which is not positive semidefinite).
    for (int k = 5; k >= 0; --k)
      if (const int z = set("payload_inertia", k, 0.0)) return z;
    std::printf("payload_inertia: refused (the estimate's noise about a point mass): left at 0\n");
    rc = 0;
  }
  return rc != 0 ? rc : set("payload_allowance", 0, 0.0);
}

/// identify --apply: the torque off (a disable), then the estimate's friction and armatures into friction_vis,
/// friction_cou, friction_sti and armature_correction, each value within its element's range (an estimate below
/// 0 is set to 0), and the payload's estimate when given (apply_identify_payload). What was set is printed; `param
/// save` keeps it.
int apply_identify(Client& c, const Args& a, const pil::IdentifyFrame& f, const pil::IdentifyPayloadFrame* p) {
  const std::uint32_t off = c.command(osc::MotionVerb::kDisable);
  if (off == 0) return report({Status::kError, 0, osc::MotionReason::kNone, 0, c.error(), {}});
  if (const Outcome o = c.wait_done(off, a.timeout); o.status != Status::kDone) return report(o);
  const struct {
    const char* name;
    const float* values;
  } sets[] = {{"friction_vis", f.friction},
              {"friction_cou", f.friction + osc::kDof},
              {"friction_sti", f.friction + 2 * osc::kDof},
              {"armature_correction", f.armature}};
  for (const auto& set : sets) {
    const int i = osc::param_index(set.name);
    for (int e = 0; e < osc::kParams[i].count; ++e) {
      const auto range = c.param(pil::kParamOpGet, i, e, 0, a.timeout);
      if (const int rc = param_status(c, range, "get")) return rc;
      const double v = std::clamp(static_cast<double>(set.values[e]), static_cast<double>(range->lo),
                                  static_cast<double>(range->hi));
      const auto r = c.param(pil::kParamOpSet, i, e, v, a.timeout);
      if (const int rc = param_status(c, r, "set")) return rc;
      print_param(i, *r);
    }
  }
  if (p)
    if (const int rc = apply_identify_payload(c, a, *p)) return rc;
  std::printf("applied, the torque off: enable goes on from them; param save keeps them for the next power-on\n");
  return 0;
}

/// identify: the run's answer and end, then the board's estimate (its identify frame), and with --apply the
/// estimate into the parameters. Exit 1 when the run was refused or aborted, its estimate failed, or --apply found
/// none to apply.
int identify(Client& c, const Args& a) {
  const std::uint32_t id = c.identify(a.payload);
  if (id == 0) return report({Status::kError, 0, osc::MotionReason::kNone, 0, c.error(), {}});
  const Outcome o = c.wait_answer(id, a.timeout);
  if (const int rc = report(o); o.status != Status::kAccepted) return rc;
  const Outcome d = c.wait_done(id, a.timeout);
  const int rc = report(d);
  const auto f = c.wait_identify(id, kIdentifyFrameWaitS);
  if (!f) {
    std::printf(
        "no estimate: the board sent no identify frame (a firmware from before the boards estimated runs the motion "
        "alone; or the frame was lost)\n");
    return a.apply ? 1 : rc;
  }
  print_identify(*f);
  if (const auto fo = c.wait_identify_offset(id, kIdentifyFrameWaitS))
    print_identify_offset(*fo);
  else
    std::printf("no offset estimate: the board sent no identify_offset frame\n");
  std::optional<pil::IdentifyPayloadFrame> p;
  if (a.payload) {
    p = c.wait_identify_payload(id, kIdentifyFrameWaitS);
    if (p)
      print_identify_payload(*p);
    else
      std::printf("no payload estimate: the board sent no identify_payload frame\n");
  }
  if (f->status != static_cast<std::uint8_t>(osc::IdentifyStatus::kOk) || (a.payload && !p)) return 1;
  return a.apply ? apply_identify(c, a, *f, p ? &*p : nullptr) : rc;
}

/// The param command line's own checks: a known operation and name, as many values as elements.
bool check_param(const Args& a, std::string& err) {
  const bool named = a.param_op == "get" || a.param_op == "set";
  if (!named) {
    if (!a.param_name.empty() || !a.param_values.empty()) return err = "param " + a.param_op + " takes no name", false;
    return true;
  }
  const int i = osc::param_index(a.param_name.c_str());
  if (i < 0) {
    err = "param " + a.param_name + ": no such parameter (";
    for (int k = 0; k < osc::kParamCount; ++k) err += std::string(k ? ", " : "") + osc::kParams[k].name;
    return err += ")", false;
  }
  const int n = osc::kParams[i].count;
  if (a.element >= n)
    return err = "param " + a.param_name + " --element " + std::to_string(a.element) + ": it has " + std::to_string(n) +
                 " element" + (n > 1 ? "s (0 to " + std::to_string(n - 1) + ")" : " (0)"),
           false;
  if (a.param_op == "get") {
    if (!a.param_values.empty()) return err = "param get takes no value", false;
    return true;
  }
  const std::size_t want = a.element >= 0 ? 1 : static_cast<std::size_t>(n);
  if (a.param_values.size() != want)
    return err = "param set " + a.param_name + ": " + std::to_string(want) + " value" + (want > 1 ? "s" : "") +
                 (a.element >= 0 ? " (one element)" : " (one per element; --element E sets one)") + ", got " +
                 std::to_string(a.param_values.size()),
           false;
  return true;
}

void add_limits(CLI::App* s, Args& a) {
  s->add_option("--v", a.v, "linear speed limit [m/s], at most the configured maximum")->check(CLI::PositiveNumber);
  s->add_option("--a", a.a, "linear acceleration limit [m/s^2]")->check(CLI::PositiveNumber);
  s->add_option("--j", a.j, "linear jerk limit [m/s^3]")->check(CLI::PositiveNumber);
  s->add_flag("--relative", a.relative, "offsets from where the queue ends (a stream: from where it starts)");
}

void build(CLI::App& app, Args& a) {
  app.description(
      "Commands a controller over the command protocol (docs/protocol.md) on a serial device or the simulator's "
      "pseudo-terminal (osc_sim --pty). Exit status 0: accepted or done; 1: refused, aborted or timed out; 2: a bad "
      "command line, port or file.");
  app.set_help_flag("-h,--help", "this text");
  app.require_subcommand(1);
  app.option_defaults()->disable_flag_override()->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  app.add_option("--port", a.port, "the serial device or pseudo-terminal (e.g. /dev/pts/7)")->required();
  app.add_option("--baud", a.baud, "baud rate of a serial device (default 115200)")->check(CLI::Range(50, 4000000));
  app.add_option("--timeout", a.timeout, "seconds to wait for an answer or an end (default 120)")
      ->check(CLI::Range(0.1, 86400.0));
  app.add_option("--keepalive", a.keepalive,
                 "while waiting, a keep-alive frame after this many seconds without a frame sent (default 0.1; 0: "
                 "none): a board with local encoders stops a motion after 0.5 s of silence on its link")
      ->check(CLI::Range(0.0, 0.4));
  app.add_subcommand("state", "print the state frame: state, stop, faults, queue, reference and measured pose");
  // The verbs' meanings are the firmware's (OSC_MOTION_VERB_LIST).
  for (osc::MotionVerb v : {osc::MotionVerb::kEnable, osc::MotionVerb::kDisable, osc::MotionVerb::kClear,
                            osc::MotionVerb::kPaper, osc::MotionVerb::kStop, osc::MotionVerb::kHome})
    app.add_subcommand(osc::motion_name(v), osc::MotionNames<osc::MotionVerb>::kDocs[static_cast<int>(v)]);
  CLI::App* id = app.add_subcommand(
      "identify", std::string(osc::MotionNames<osc::MotionVerb>::kDocs[static_cast<int>(osc::MotionVerb::kIdentify)]) +
                      "; waits for its end and prints the board's estimate");
  id->add_flag("--apply", a.apply,
               "then the estimate's friction and armatures into the parameters friction_vis, friction_cou, "
               "friction_sti and armature_correction (the torque off first: a disable), with --payload the payload's "
               "into payload_mass, payload_com and payload_inertia; param save keeps them");
  id->add_flag("--payload", a.payload,
               "estimate the payload at the flange too: its mass, centre of mass and inertia (all ten of its inertial "
               "parameters, with the arm's own model: the whole payload, whatever is set)");
  std::string poses;
  for (int i = 0; i < osc::robot::kNamedPoseCount; ++i)
    poses += std::string(i ? ", " : "") + osc::robot::kNamedPoses[i].name;
  CLI::App* dp = app.add_subcommand(
      "declare_pose",
      std::string(osc::MotionNames<osc::MotionVerb>::kDocs[static_cast<int>(osc::MotionVerb::kDeclarePose)]) +
          " (torque off)");
  dp->add_option("pose", a.pose, "the pose's name: " + poses)->required()->check([](const std::string& v) {
    return osc::robot::named_pose_code(v) >= 0 ? std::string() : "'" + v + "' is not a named pose";
  });
  CLI::App* mv = app.add_subcommand("move", "a jerk-limited move_to of the wrist centre; waits until done");
  mv->add_option("xyz", a.xyz, "X Y Z [m], base frame")->expected(3)->required();
  mv->add_option("--rpy", a.rpy, "roll pitch yaw [deg] of the target orientation")->expected(3);
  mv->add_flag("--replace", a.replace, "re-target the running motion instead of queueing");
  mv->add_flag("--no-wait", a.no_wait, "return once accepted");
  add_limits(mv, a);
  CLI::App* st = app.add_subcommand("stream", "stream a CSV path (t, x, y, z[, roll, pitch, yaw] in s, m, deg)");
  st->add_option("file", a.csv, "the path, CSV")->required();
  st->add_option("--rate", a.rate, "setpoints per second: 1000 / N for a whole N from 1 to 100")
      ->required()
      ->check(CLI::Range(10.0, 1000.0));
  st->add_flag("--velocity", a.velocity,
               "send each setpoint with the path's velocity (its slope between rows): no delay of one period");
  add_limits(st, a);
  CLI::App* pm = app.add_subcommand(
      "param",
      "the controller's parameters (docs/protocol.md, \"Parameters\"): list, get, set, save, load, reset, check");
  std::vector<std::string> ops = {"list"};
  for (const char* n : pil::kParamOpNames) ops.emplace_back(n);
  pm->add_option("op", a.param_op, "list, get NAME, set NAME VALUE..., save, load, reset, check")
      ->required()
      ->check(CLI::IsMember(ops));
  pm->add_option("name", a.param_name, "the parameter (get, set)");
  pm->add_option("values", a.param_values, "set: one value per element, or one with --element");
  pm->add_option("--element", a.element, "get, set: only this element of a vector parameter")
      ->check(CLI::Range(0, 255));
  CLI::App* w = app.add_subcommand("watch", "print state changes and every answer");
  w->add_option("--seconds", a.seconds, "for this long (default: until interrupted)")->check(CLI::PositiveNumber);
}

int run(Client& c, const Args& a) {
  if (a.verb == "state") return state(c, a);
  if (a.verb == "move") return move(c, a);
  if (a.verb == "stream") return stream(c, a);
  if (a.verb == "watch") return watch(c, a);
  if (a.verb == "param") return param(c, a);
  if (a.verb == "declare_pose") return declare_pose(c, a);
  if (a.verb == "identify") return identify(c, a);
  const osc::MotionVerb verb = a.verb == "enable"    ? osc::MotionVerb::kEnable
                               : a.verb == "disable" ? osc::MotionVerb::kDisable
                               : a.verb == "clear"   ? osc::MotionVerb::kClear
                               : a.verb == "paper"   ? osc::MotionVerb::kPaper
                               : a.verb == "home"    ? osc::MotionVerb::kHome
                                                     : osc::MotionVerb::kStop;
  return simple(c, a, verb);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("", "oscctl");
  Args a;
  build(app, a);
  // A word that is no command: CLI11 says only that one is required.
  auto what = [&](const CLI::ParseError& e) {
    const std::vector<std::string> extra = app.remaining();
    return app.get_subcommands().empty() && !extra.empty()
               ? extra.front() +
                     ": not a command (state, enable, disable, clear, paper, stop, home, identify, declare_pose, move, "
                     "stream, "
                     "watch, "
                     "param)"
               : std::string(e.what());
  };
  if (const int status = sim::parse_command_line(app, argc, argv, "oscctl", "the commands and options", what);
      status >= 0)
    return status;
  a.verb = app.get_subcommands().front()->get_name();
  std::string err;
  if ((a.verb == "stream" && !check_stream(a, err)) || (a.verb == "param" && !check_param(a, err))) {
    std::fprintf(stderr, "oscctl: %s\n", err.c_str());
    return 2;
  }
  auto t = osc::client::SerialTransport::open(a.port, a.baud, err);
  if (!t) {
    std::fprintf(stderr, "oscctl: --port %s\n", err.c_str());
    return 2;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  Client c(std::move(t));
  c.keepalive_s = a.keepalive;
  return run(c, a);
}
