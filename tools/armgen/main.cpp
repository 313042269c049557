// armgen SHEET [--urdf FILE] [--root DIR] [--output FILE] [--check FILE]
// Generates an arm's constant table from its drive sheet and the URDF the sheet names (docs/arms.md).
// Exit 0: written (stdout, or --output); 1: --check's file differs (stale_header); 2: the
// description is refused (armgen: error: <name>: <what, where>).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "armgen.hpp"

namespace fs = std::filesystem;

namespace {

/// `path` relative to `root` when it lies under it (the banner names the files so).
std::string shown(const fs::path& path, const fs::path& root) {
  const fs::path rel = fs::weakly_canonical(path).lexically_relative(fs::weakly_canonical(root));
  if (rel.empty() || rel.native().rfind("..", 0) == 0) return path.generic_string();
  return rel.generic_string();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"armgen: an arm's URDF and drive sheet to the firmware's constant table (docs/arms.md)"};
  std::string sheet_path, urdf_override, root = ".", output, check;
  app.add_option("sheet", sheet_path, "the arm's drive sheet (YAML); it names its URDF")->required();
  app.add_option("--urdf", urdf_override, "read this URDF instead of the sheet's");
  app.add_option("--root", root, "the repository root: the banner names the files relative to it");
  app.add_option("--output,-o", output, "write the header here (default: standard output)");
  app.add_option("--check", check,
                 "compare with this (committed) header; exit 1 with the command to regenerate when it differs");
  CLI11_PARSE(app, argc, argv);

  std::string header;
  try {
    const armgen::Sheet sheet = armgen::read_sheet(sheet_path);
    const fs::path urdf =
        urdf_override.empty() ? fs::path(sheet_path).parent_path() / sheet.urdf : fs::path(urdf_override);
    const armgen::Chain chain = armgen::read_chain(urdf.string(), sheet);
    armgen::check_description(sheet, chain);
    header = armgen::emit_header(sheet, chain, shown(sheet_path, root), shown(urdf, root));
  } catch (const armgen::Error& e) {
    std::cerr << "armgen: error: " << e.name << ": " << e.what() << "\n";
    return 2;
  }
  if (output.empty() && check.empty()) std::cout << header;
  if (!output.empty()) {
    std::ofstream out(output, std::ios::binary);
    out << header;
    if (!out) {
      std::cerr << "armgen: error: output: cannot write " << output << "\n";
      return 2;
    }
  }
  if (!check.empty()) {
    std::ifstream in(check, std::ios::binary);
    std::stringstream committed;
    committed << in.rdbuf();
    if (!in || committed.str() != header) {
      std::cerr << "armgen: error: stale_header: " << check << " differs from what " << sheet_path << " generates"
                << (output.empty() ? "" : " (" + output + ")")
                << ". Nobody edits it by hand: regenerate it with scripts/gen_arms.sh and commit it.\n";
      return 1;
    }
  }
  return 0;
}
