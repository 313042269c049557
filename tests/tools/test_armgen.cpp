// tools/armgen run as the build runs it: the committed tables are what their descriptions generate,
// the good descriptions are accepted, and each malformed description (tests/tools/armgen_cases/) is
// refused with exit status 2 and its error's name (`armgen: error: <name>: ...`).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace {

struct Outcome {
  int status;
  std::string output;  // stdout and stderr
};

Outcome armgen(const std::string& args) {
  const std::string cmd = std::string(ARMGEN_PATH) + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  Outcome r{-1, ""};
  if (!p) return r;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int w = pclose(p);
  r.status = WIFEXITED(w) ? WEXITSTATUS(w) : -1;
  return r;
}

const std::string kCases = ARMGEN_CASES;
const std::string kSource = OSC_SOURCE_DIR;

TEST(Armgen, CommittedTablesAreCurrent) {
  for (const char* arm : {"puma560", "ur5e"}) {
    const Outcome r = armgen(kSource + "/firmware/robots/" + arm + "/" + arm + ".yaml --root " + kSource + " --check " +
                             kSource + "/firmware/robots/include/osc/robots/" + arm + ".hpp");
    EXPECT_EQ(r.status, 0) << arm << ": " << r.output;
  }
}

TEST(Armgen, GoodDescriptionsAreAccepted) {
  for (const char* sheet : {"good.yaml", "twisted.yaml"}) {
    const Outcome r = armgen(kCases + "/" + sheet);
    EXPECT_EQ(r.status, 0) << sheet << ": " << r.output;
    EXPECT_NE(r.output.find("constexpr ArmDescription kArm"), std::string::npos) << sheet;
  }
}

TEST(Armgen, AStaleTableFailsTheCheckNamingTheCommand) {
  const Outcome r = armgen(kCases + "/good.yaml --check " + kCases + "/good.urdf");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("armgen: error: stale_header: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("scripts/gen_arms.sh"), std::string::npos) << r.output;
}

struct Case {
  const char* file;   // a URDF (with good.yaml) or a sheet (with the URDF it names)
  const char* error;  // the error's name
};

class ArmgenRefuses : public testing::TestWithParam<Case> {};

TEST_P(ArmgenRefuses, WithExitStatusTwoAndTheErrorsName) {
  const std::string file = GetParam().file;
  const bool urdf = file.size() > 5 && file.substr(file.size() - 5) == ".urdf";
  const Outcome r = armgen(urdf ? kCases + "/good.yaml --urdf " + kCases + "/" + file : kCases + "/" + file);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(std::string("armgen: error: ") + GetParam().error + ": "), std::string::npos) << r.output;
}

const Case kCasesList[] = {
    {"urdf_parse.urdf", "urdf_parse"},
    {"not_a_number.urdf", "urdf_parse"},
    {"nan_mass.urdf", "not_finite"},
    {"five_joints.urdf", "chain_joints"},
    {"branched.urdf", "chain_joints"},
    {"mimic.urdf", "mimic_joint"},
    {"prismatic.urdf", "joint_type"},
    {"missing_inertial.urdf", "missing_inertial"},
    {"zero_mass.urdf", "mass_not_positive"},
    {"triangle.urdf", "inertia_not_positive_definite"},
    {"negative_inertia.urdf", "inertia_not_positive_definite"},
    {"limits_inverted.urdf", "limits_inverted"},
    {"zero_axis.urdf", "zero_axis"},
    {"huge_mass.urdf", "fixed_point_range"},
    {"long_arm.urdf", "fixed_point_range"},
    {"tiny_inertia.urdf", "fixed_point_resolution"},
    {"sheet_parse.yaml", "sheet_parse"},
    {"missing_field.yaml", "sheet_missing_field"},
    {"wrong_length.yaml", "sheet_wrong_length"},
    {"no_source.yaml", "sheet_no_source"},
    {"unknown_field.yaml", "sheet_unknown_field"},
    {"zero_gear.yaml", "sheet_value"},
    {"narrow_current.yaml", "sheet_value"},
    {"nan.yaml", "not_finite"},
    {"pose_outside.yaml", "pose_outside_limits"},
    {"huge_gear.yaml", "fixed_point_range"},
    {"operational_frame.yaml", "operational_frame"},
};

std::string case_name(const testing::TestParamInfo<Case>& info) {
  std::string n = info.param.file;
  for (char& c : n)
    if (c == '.') c = '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Cases, ArmgenRefuses, testing::ValuesIn(kCasesList), case_name);

}  // namespace
