// SPDX-License-Identifier: Apache-2.0
// vinebot: one binary, one subcommand per job (COLMAP's exe/colmap.cc). main() sets glibc's heap
// thresholds and dispatches.
#include <malloc.h>

#include <cstring>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/flags.h"

namespace {

struct Command {
  const char* name;  // may be two words ("sim render")
  const char* usage;
  std::function<absl::Status(vb::app::Flags&)> run;
};

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"sim render",
       "--seed S --vine K --out DIR [--pixel-format rgb8|mono8|bayer_rg8|...] "
       "[--calibration-error-px X] [--cameras N] [--no-neighbours] [--no-noise] [--noise-seed N]",
       vb::app::RunSimRender},
      {"capture",
       "--source sim|aravis --out DIR [--exposure-us U] [--gain-db G] [--trigger software|free] "
       "[--timeout-s T] [--row NAME] [--position-m X]\n"
       "      sim:    [--seed S --vine K --pixel-format F --calibration-error-px X]\n"
       "      aravis: --devices cam0=ADDR,cam1=ADDR,... --calibration calibration.yaml "
       "[--pixel-format F]",
       vb::app::RunCapture},
      {"bundle info", "--bundle DIR", vb::app::RunBundleInfo},
      {"reconstruct",
       "--bundle DIR --out model.json [--deadline-s T] [--alpha A] [--select-context]"
       " [--context-alpha A] [--sweep false] [--head-peel] [--head-min-cell M]"
       " [--head-depth-factor F] [--head-leaf-fraction F] [--head-centre-on-trunk]"
       " [--head-leaf-wood-px X]"
       " [--head-bases] [--head-bases-reach M] [--head-bases-thick-views N]"
       " [--head-bases-inside M] [--strand-halves] [--strand-halves-dip G]"
       " [--sweep-*, --head-exit-*, --extend-*, --keep-*:"
       " app/reconstruct_flags.h]",
       vb::app::RunReconstruct},
      {"evaluate",
       "--model model.json --truth ground_truth.json [--policy policy.json] "
       "[--calibration calibration.yaml]",
       vb::app::RunEvaluate},
      {"decide",
       "--model model.json [--policy policy.json] [--weights weights.json] [--deadline-s T] "
       "--out cut_plan.json",
       vb::app::RunDecide},
      {"phenomics",
       "--model model.json [--plan cut_plan.json | --policy policy.json [--weights weights.json]]"
       "\n      without --plan, the plan is decided here so pruning weight and kept length are "
       "filled in",
       vb::app::RunPhenomics},
      {"bench reconstruct",
       "--vines N --seed-base S [--calibration-error-px X] [--policy policy.json]"
       " [--input images|labels|truth] [--rig-refine off|canes|trellis] [--alpha A]"
       " [--select-context] [--context-alpha A] [--head-peel] [--head-min-cell M]"
       " [--head-depth-factor F] [--head-leaf-fraction F] [--head-centre-on-trunk]"
       " [--head-leaf-wood-px X] [--sweep false]"
       " [--grow-refit M] [--grow-max-length M] [--head-bases] [--head-bases-reach M]"
       " [--head-bases-thick-views N] [--head-bases-inside M] [--strand-halves]"
       " [--strand-halves-dip G] [--tolerances-mm 15,20,30]"
       " [--sweep-*, --head-exit-*, --extend-*, --keep-*: app/reconstruct_flags.h]",
       vb::app::RunBenchReconstruct},
      {"plan",
       "--model model.json --cuts cut_plan.json --out trajectory.json [--tool mill_end|secateur] "
       "[--checker primitives|fcl_primitives|fcl_mesh] [--deadline-s T]",
       vb::app::RunPlan},
      {"bench plan",
       "--vines N --seed-base S [--checkers primitives,fcl_primitives,fcl_mesh] [--verify] "
       "[--tool T] [--json]",
       vb::app::RunBenchPlan},
      {"train segmenter", "--out FILE [--vines N --seed-base S]", vb::app::RunTrainSegmenter},
      {"sim decide-labels", "--vines N --out DIR [--seed-base S] [--policy policy.json]",
       vb::app::RunSimDecideLabels},
      {"train decide",
       "--labels DIR [--holdout DIR | --holdout-fraction F] [--epochs N] [--regularization L] "
       "[--keep-loss K] [--out weights.json]",
       vb::app::RunTrainDecide},
  };
  return commands;
}

void PrintUsage(std::ostream& out) {
  out << "usage: vinebot COMMAND [flags]\n\ncommands:\n";
  for (const Command& c : Commands()) out << "  vinebot " << c.name << " " << c.usage << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  // glibc keeps freed blocks of up to 32 MB in the heap for reuse, and up to 256 MB of free heap
  // before returning it. A stop allocates and frees images and maps of 1-5 MB; with glibc's
  // defaults (a 128 KB mmap threshold, raised only as such blocks are freed) each could be a
  // fresh mapping whose pages fault in again, at a cost that depended on the run's allocation
  // history: the head stage took 0.12 s a stop on tuning stops 1600-1629 and 0.04 s with these
  // settings (docs/benchmarks.md, session 26).
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  if (argc < 2 || std::strcmp(argv[1], "help") == 0 || std::strcmp(argv[1], "--help") == 0) {
    PrintUsage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  for (const Command& c : Commands()) {
    const std::string name = c.name;
    const size_t space = name.find(' ');
    int first = 2;
    if (space == std::string::npos) {
      if (name != argv[1]) continue;
    } else {
      if (argc < 3 || name.substr(0, space) != argv[1] || name.substr(space + 1) != argv[2])
        continue;
      first = 3;
    }
    auto flags = vb::app::Flags::Parse(argc, argv, first);
    absl::Status status = flags.ok() ? c.run(*flags) : flags.status();
    if (!status.ok()) {
      std::cerr << "vinebot " << name << ": " << status.message() << "\n";
      return status.code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
    }
    return 0;
  }
  std::cerr << "vinebot: unknown command '" << argv[1] << "'\n";
  PrintUsage(std::cerr);
  return 2;
}
