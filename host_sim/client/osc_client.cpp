#include "osc_client.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <thread>

#include "osc/control/faults.hpp"

namespace osc::client {

bool set_custom_baud(int fd, int baud);  // serial_baud.cpp: termios2, apart from <termios.h>

namespace {

constexpr std::size_t kHistory = 1024;  // answers kept for wait_answer / wait_done

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// The termios code of a standard baud rate (B0: none).
speed_t standard_baud(int baud) {
  static const struct {
    int baud;
    speed_t code;
  } kRates[] = {
      {50, B50},           {75, B75},           {110, B110},         {134, B134},         {150, B150},
      {200, B200},         {300, B300},         {600, B600},         {1200, B1200},       {1800, B1800},
      {2400, B2400},       {4800, B4800},       {9600, B9600},       {19200, B19200},     {38400, B38400},
      {57600, B57600},     {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
      {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000}, {1500000, B1500000},
      {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000}, {3500000, B3500000}, {4000000, B4000000}};
  for (const auto& r : kRates)
    if (r.baud == baud) return r.code;
  return B0;
}

/// A verb whose command runs a motion that ends done (done_id) or aborted: move_to, paper, stream, home, identify.
bool motion_verb(std::uint8_t v) {
  for (MotionVerb m :
       {MotionVerb::kMoveTo, MotionVerb::kPaper, MotionVerb::kStream, MotionVerb::kHome, MotionVerb::kIdentify})
    if (v == static_cast<std::uint8_t>(m)) return true;
  return false;
}

template <class E>
const char* name_of(std::uint8_t code) {
  return motion_name(static_cast<E>(code));
}

std::string pose_text(const float x[6]) {
  char buf[160];
  constexpr double kDeg = 180.0 / kPi;
  std::snprintf(buf, sizeof buf, "%.4f %.4f %.4f m, rpy %.2f %.2f %.2f deg", x[0], x[1], x[2], x[3] * kDeg, x[4] * kDeg,
                x[5] * kDeg);
  return buf;
}

}  // namespace

// ------------------------------------------------------------------------------------------ transport

std::unique_ptr<SerialTransport> SerialTransport::open(const std::string& path, int baud, std::string& err) {
  if (baud < 50 || baud > 4000000) return err = "baud " + std::to_string(baud) + ": 50 to 4000000", nullptr;
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) return err = path + ": " + std::strerror(errno), nullptr;
  termios t{};
  if (!isatty(fd) || tcgetattr(fd, &t) != 0) {
    close(fd);
    return err = path + ": not a serial device or terminal", nullptr;
  }
  cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~(CSTOPB | CRTSCTS);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  const speed_t code = standard_baud(baud);
  if (code != B0) cfsetspeed(&t, code);
  bool ok = tcsetattr(fd, TCSANOW, &t) == 0;
  if (ok && code == B0) ok = set_custom_baud(fd, baud);
  if (!ok) {
    const std::string why = std::strerror(errno);
    close(fd);
    return err = path + ": cannot set raw mode at " + std::to_string(baud) + " baud: " + why, nullptr;
  }
  tcflush(fd, TCIOFLUSH);  // an earlier client's unread bytes
  return std::unique_ptr<SerialTransport>(new SerialTransport(fd, path));
}

SerialTransport::~SerialTransport() { close(fd_); }

int SerialTransport::read(std::uint8_t* buf, int n, double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  const double t = std::max(0.0, timeout_s);
  const timespec ts{static_cast<time_t>(t), static_cast<long>((t - std::floor(t)) * 1e9)};
  const int r = ppoll(&p, 1, &ts, nullptr);
  if (r < 0 && errno == EINTR) return 0;
  if (r < 0) return error_ = path_ + ": " + std::strerror(errno), -1;
  if (r == 0) return 0;
  const ssize_t k = ::read(fd_, buf, static_cast<std::size_t>(n));
  if (k > 0) return static_cast<int>(k);
  if (k < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
  error_ = path_ + (k == 0 || errno == EIO ? ": hung up (the board or the simulator has gone)"
                                           : ": " + std::string(std::strerror(errno)));
  return -1;
}

bool SerialTransport::write(const std::uint8_t* buf, int n) {
  while (n > 0) {
    const ssize_t k = ::write(fd_, buf, static_cast<std::size_t>(n));
    if (k > 0) {
      buf += k, n -= static_cast<int>(k);
      continue;
    }
    if (k < 0 && errno != EAGAIN && errno != EINTR) return error_ = path_ + ": " + std::strerror(errno), false;
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, 1000) == 0) return error_ = path_ + ": cannot write (nothing reads the other end)", false;
  }
  return true;
}

// ------------------------------------------------------------------------------------------ text

const char* status_name(Status s) {
  switch (s) {
    case Status::kAccepted:
      return "accepted";
    case Status::kDone:
      return "done";
    case Status::kRefused:
      return "refused";
    case Status::kAborted:
      return "aborted";
    case Status::kTimeout:
      return "timeout";
    case Status::kError:
      return "error";
  }
  return "?";
}

std::string Outcome::text() const {
  std::string s = status_name(status);
  if (status == Status::kRefused || status == Status::kAborted) s += std::string(": ") + motion_name(reason);
  if (status == Status::kRefused && reason == MotionReason::kFaulted) s += " (" + fault_names(cause) + ")";
  if (status == Status::kError) s += ": " + error;
  return s;
}

std::string fault_names(std::uint32_t bits) {
  if (bits == 0) return "none";
  std::string s;
  for (int i = 0; i < 32; ++i) {
    if (!(bits & (1u << i))) continue;
    if (!s.empty()) s += ",";
    s += i < kFaultCount ? kFaultNames[i] : "bit" + std::to_string(i);
  }
  return s;
}

std::string friction_fit_text(std::uint8_t checked, std::uint8_t stale) {
  std::string t;
  for (int i = 0; i < kDof; ++i) {
    t += i ? ", J" : "J";
    t += std::to_string(i + 1);
    t += !(checked >> i & 1u) ? " -" : (stale >> i & 1u) ? " stale" : " fits";
  }
  return t;
}

std::string state_text(const pil::StateFrame& s) {
  std::string t;
  t += std::string("state: ") + name_of<MotionState>(s.state) + "\n";
  t += std::string("stop: ") + name_of<StopCategory>(s.stop) + "\n";
  t += "faults: " + fault_names(s.faults) + "\n";
  t += "queued: " + std::to_string(s.queued) + "\n";
  t += "running_id: " + std::to_string(s.running_id) + "\n";
  t += "reference: " + pose_text(s.x_d) + "\n";
  t += "measured: " + pose_text(s.x) + "\n";
  t += "dropped: " + std::to_string(s.dropped) + "\n";
  t += "tick: " + std::to_string(s.tick) + "\n";
  t += "friction_fit: " + friction_fit_text(s.friction_checked, s.friction_stale) + "\n";
  return t;
}

std::string answer_text(const pil::AnswerFrame& a) {
  // Appended piece by piece: GCC 12's -Wrestrict misreads chained string concatenations.
  std::string t = "tick ";
  t += std::to_string(a.tick);
  t += ":";
  if (a.outcome != static_cast<std::uint8_t>(CommandOutcome::kNone)) {
    t += " ";
    t += name_of<MotionVerb>(a.verb);
    t += " ";
    t += std::to_string(a.id);
    t += " ";
    t += name_of<CommandOutcome>(a.outcome);
    if (a.outcome == static_cast<std::uint8_t>(CommandOutcome::kRefused)) {
      t += ": ";
      t += name_of<MotionReason>(a.refusal);
    }
    if (a.cause != 0) {
      t += " (";
      t += fault_names(a.cause);
      t += ")";
    }
    t += ";";
  }
  if (a.done_id != 0) {
    t += " done ";
    t += std::to_string(a.done_id);
    t += ";";
  }
  if (a.abort != static_cast<std::uint8_t>(MotionReason::kNone)) {
    t += " aborted ";
    t += std::to_string(a.aborted_id);
    t += ": ";
    t += name_of<MotionReason>(a.abort);
    t += ";";
  }
  if (a.completion != static_cast<std::uint8_t>(MotionCompletion::kNone)) {
    t += " completion ";
    t += name_of<MotionCompletion>(a.completion);
    t += ";";
  }
  t += " state ";
  t += name_of<MotionState>(a.state);
  t += ", queued ";
  t += std::to_string(a.queued);
  return t;
}

// ------------------------------------------------------------------------------------------ client

Client::Client(std::unique_ptr<Transport> transport) : t_(std::move(transport)) {
  // Ids unique across clients of one controller: a new client's answers are never an earlier one's.
  std::random_device rd;
  next_id_ = (rd() & 0x3FFFFFFFu) + 1;
}

bool Client::send(const std::uint8_t* buf, int n) {
  last_write_s_ = now_s();
  if (t_->write(buf, n)) return true;
  error_ = t_->error();
  return false;
}

std::uint32_t Client::command(MotionVerb verb, const MoveRequest<double>& req, std::uint8_t flags) {
  const std::uint32_t id = next_id_++;
  if (next_id_ == 0) next_id_ = 1;
  std::uint8_t buf[pil::kMaxFrame];
  pil::CommandFrame f = frame_from_command(id, verb, req);
  f.flags = static_cast<std::uint8_t>(f.flags | flags);
  const int n = pil::encode(f, buf);
  sent_.emplace_back(id, std::vector<std::uint8_t>(buf, buf + n));
  if (sent_.size() > kSentKept) sent_.pop_front();
  return send(buf, n) ? id : 0;
}

bool Client::resend(std::uint32_t id) {
  for (const auto& [sent_id, frame] : sent_)
    if (sent_id == id) return send(frame.data(), static_cast<int>(frame.size()));
  return true;
}

void Client::dispatch() {
  pil::AnswerFrame a;
  pil::StateFrame s;
  pil::ParamAnswerFrame p;
  pil::IdentifyFrame f;
  pil::IdentifyPayloadFrame fp;
  pil::IdentifyOffsetFrame fo;
  if (parser_.decode(p)) {
    param_answer_ = p;
  } else if (parser_.decode(f)) {
    identify_ = f;
  } else if (parser_.decode(fp)) {
    identify_payload_ = fp;
  } else if (parser_.decode(fo)) {
    identify_offset_ = fo;
  } else if (parser_.decode(a)) {
    answers_.push_back(a);
    if (answers_.size() > kHistory) answers_.pop_front();
    if (on_answer) on_answer(a);
  } else if (parser_.decode(s)) {
    state_ = s;
    ++states_seen_;
    if (on_state) on_state(s);
  }
}

template <class F>
std::optional<F> Client::wait_run_frame(const std::optional<F>& last, std::uint32_t id, double timeout_s) {
  const auto got = [&] { return last && last->id == id; };
  if (!read_until(now_s() + timeout_s, got) && !got()) return std::nullopt;
  return last;
}

std::optional<pil::IdentifyFrame> Client::wait_identify(std::uint32_t id, double timeout_s) {
  return wait_run_frame(identify_, id, timeout_s);
}

std::optional<pil::IdentifyPayloadFrame> Client::wait_identify_payload(std::uint32_t id, double timeout_s) {
  return wait_run_frame(identify_payload_, id, timeout_s);
}

std::optional<pil::IdentifyOffsetFrame> Client::wait_identify_offset(std::uint32_t id, double timeout_s) {
  return wait_run_frame(identify_offset_, id, timeout_s);
}

bool Client::read_until(double deadline, const std::function<bool()>& done) {
  std::uint8_t buf[256];
  while (!done()) {
    const double left = deadline - now_s();
    if (left <= 0) return false;
    if (keepalive_s > 0 && now_s() - last_write_s_ >= keepalive_s) {
      std::uint8_t frame[pil::kMaxFrame];
      if (!send(frame, pil::encode(pil::StateFrame{}, frame))) return false;
    }
    const int n = t_->read(buf, sizeof buf, std::min({left, 0.05, keepalive_s > 0 ? keepalive_s : 0.05}));
    if (n < 0) return error_ = t_->error(), false;
    const double now = now_s();
    if (n > 0) last_read_s_ = now;
    for (int i = 0; i < n; ++i) take(parser_.feed(buf[i]));
    // A frame begun and silent for the in-frame timeout: cut short, its bytes scanned again.
    if (n == 0 && parser_.in_frame() && now - last_read_s_ >= params::kFrameTimeout) take(parser_.expire());
  }
  return true;
}

void Client::take(pil::Parser::Result r) {
  for (; r != pil::Parser::kPending; r = parser_.next()) {
    if (r == pil::Parser::kFrame)
      dispatch();
    else
      link_errors_[pil::Parser::error_of(r)] +=
          r == pil::Parser::kJunk ? static_cast<std::uint32_t>(parser_.junk()) : 1u;
  }
}

bool Client::pump(double timeout_s) {
  read_until(now_s() + timeout_s, [] { return false; });
  return error_.empty();
}

std::optional<pil::ParamAnswerFrame> Client::param(std::uint8_t op, int index, int element, double value,
                                                   double timeout_s) {
  if (index < 0 || index > 255 || element < 0 || element > 255)
    return error_ = "param: index and element are 0 to 255", std::nullopt;
  pil::ParamFrame f;
  f.id = next_id_++;
  if (next_id_ == 0) next_id_ = 1;
  f.op = op;
  f.index = static_cast<std::uint8_t>(index);
  f.element = static_cast<std::uint8_t>(element);
  f.value = static_cast<float>(value);
  std::uint8_t buf[pil::kMaxFrame];
  if (!send(buf, pil::encode(f, buf))) return std::nullopt;
  if (!read_until(now_s() + timeout_s, [&] { return param_answer_ && param_answer_->id == f.id; })) {
    if (error_.empty()) error_ = "param: no answer within " + std::to_string(timeout_s) + " s";
    return std::nullopt;
  }
  if (param_answer_->layout != kParamLayout || param_answer_->count != kParamCount)
    return error_ = "param: the controller's parameter table (layout " + std::to_string(param_answer_->layout) + ", " +
                    std::to_string(param_answer_->count) + " parameters) is not this client's (layout " +
                    std::to_string(kParamLayout) + ", " + std::to_string(kParamCount) +
                    "): use the client of its build",
           std::nullopt;
  return param_answer_;
}

std::optional<pil::StateFrame> Client::state(double timeout_s) {
  const std::uint64_t seen = states_seen_;
  if (!read_until(now_s() + timeout_s, [&] { return states_seen_ > seen; })) return std::nullopt;
  return state_;
}

Outcome Client::evaluate(std::uint32_t id, bool until_done) const {
  Outcome o;
  o.id = id;
  bool accepted = false, wait_rest = false, motion = false;
  for (const pil::AnswerFrame& a : answers_) {
    if (!accepted) {
      if (a.id != id || a.outcome == static_cast<std::uint8_t>(CommandOutcome::kNone)) continue;
      o.answer = a;
      if (a.outcome == static_cast<std::uint8_t>(CommandOutcome::kRefused)) {
        o.status = Status::kRefused, o.reason = static_cast<MotionReason>(a.refusal), o.cause = a.cause;
        return o;
      }
      accepted = true;
      o.status = Status::kAccepted;
      if (!until_done) return o;
      motion = motion_verb(a.verb);
      wait_rest = !motion && a.state == static_cast<std::uint8_t>(MotionState::kStopping);
      if (!motion && !wait_rest) return o.status = Status::kDone, o;
      continue;
    }
    if (wait_rest && a.completion != static_cast<std::uint8_t>(MotionCompletion::kNone))
      return o.answer = a, o.status = Status::kDone, o;
    // A motion ends in exactly one answer frame naming it: done, or aborted with a reason (a move
    // still queued when the motion ahead of it was stopped, re-targeted or faulted: dropped).
    if (!motion || !answer_ends(a, id)) continue;
    o.answer = a;
    if (a.done_id == id) return o.status = Status::kDone, o;
    return o.status = Status::kAborted, o.reason = static_cast<MotionReason>(a.abort), o;
  }
  o.status = Status::kTimeout;
  return o;
}

Outcome Client::wait_answer(std::uint32_t id, double timeout_s) {
  Outcome o;
  const double deadline = now_s() + timeout_s;
  // Without an answer the same frame again every kResendS: the board runs it once (docs/protocol.md).
  for (double until = std::min(deadline, now_s() + kResendS);; until = std::min(deadline, until + kResendS)) {
    if (read_until(until, [&] { return (o = evaluate(id, false)).status != Status::kTimeout; })) break;
    if (until >= deadline || !error_.empty() || !resend(id)) break;
  }
  if (o.status == Status::kTimeout && !error_.empty()) o.status = Status::kError, o.error = error_;
  return o;
}

Outcome Client::wait_done(std::uint32_t id, double timeout_s) {
  const double deadline = now_s() + timeout_s;
  Outcome o = wait_answer(id, timeout_s);  // resent until answered
  if (o.status != Status::kAccepted) return o;
  read_until(deadline, [&] {
    o = evaluate(id, true);
    return o.status != Status::kTimeout && o.status != Status::kAccepted;
  });
  if ((o.status == Status::kTimeout || o.status == Status::kAccepted) && !error_.empty())
    o.status = Status::kError, o.error = error_;
  else if (o.status == Status::kAccepted)
    o.status = Status::kTimeout;
  return o;
}

Outcome Client::stream(const std::vector<StreamPoint>& points, bool has_rpy, double rate_hz, bool relative,
                       const CartesianLimits<double>* limits, double answer_timeout_s, bool velocity) {
  Outcome o;
  const double period = 1000.0 / rate_hz;
  const long ms = std::lround(period);
  if (!(rate_hz > 0) || std::fabs(period - static_cast<double>(ms)) > 1e-9 || ms < 1 || ms > pil::kStreamMaxPeriod) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "rate %g Hz: 1000 / N Hz for a whole N from 1 to %d (1000, 500, 250, 100, 50, 20, 10 ...)", rate_hz,
                  pil::kStreamMaxPeriod);
    o.status = Status::kError;
    o.error = buf;
    return o;
  }
  if (points.empty()) return o.status = Status::kError, o.error = "a stream needs at least one setpoint", o;
  MoveRequest<double> req;
  req.period = static_cast<std::uint32_t>(ms);
  req.relative = relative;
  if (limits) req.has_limits = true, req.limits = *limits;
  const std::uint32_t id = command(MotionVerb::kStream, req);
  if (id == 0) return o.status = Status::kError, o.error = error_, o;
  o = wait_answer(id, answer_timeout_s);
  if (o.status != Status::kAccepted) return o;
  const double t0 = now_s(), T = 1.0 / rate_hz;
  for (std::size_t n = 0; n < points.size(); ++n) {
    const bool last = n + 1 == points.size();
    // Behind the schedule (its successor is due already): skipped rather than sent in a burst.
    if (!last && now_s() >= t0 + static_cast<double>(n + 1) * T) {
      ++o.skipped;
      continue;
    }
    // Until this setpoint's time: the answers meanwhile (a stop, a stale stream end it).
    const bool ended = read_until(t0 + static_cast<double>(n) * T, [&] {
      const Outcome e = evaluate(id, true);
      return e.status == Status::kAborted || e.status == Status::kDone;
    });
    if (!error_.empty()) return o.status = Status::kError, o.error = error_, o;
    if (ended) {
      const std::uint32_t skipped = o.skipped;
      o = evaluate(id, true);
      o.skipped = skipped;
      return o;
    }
    const StreamPoint& p = points[n];
    std::uint8_t buf[pil::kMaxFrame];
    const int len =
        velocity
            ? pil::encode(setpoint_velocity_frame<double>(id, p.position, has_rpy ? &p.rpy : nullptr, p.velocity, last),
                          buf)
            : pil::encode(setpoint_frame<double>(id, p.position, has_rpy ? &p.rpy : nullptr, last), buf);
    if (!send(buf, len)) return o.status = Status::kError, o.error = error_, o;
  }
  return o;
}

}  // namespace osc::client
