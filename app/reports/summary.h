#pragma once
// summary.yaml (docs/reports.md): the validation's figures (app/processing/validation_summary.h)
// written, and the one value a later command reads back from it.

#include <map>
#include <optional>
#include <string>

#include "app/processing/validation_summary.h"

namespace irdist {

// The top-level best_dt_ms of a summary.yaml (nullopt when it is null). Throws EstimatesFileError
// naming the file when it cannot be read.
std::optional<double> ReadBestDtMs(const std::string& summary_yaml_path);

// summary.yaml: `count`, `distance_rel_error_pct: {median, p95, max}`, ... for the first method at
// top level (the default pipeline), and one block per other method (`i0_dependent:`, `geometric:`).
// Each method named in `crb` carries a `crb:` block, the Cramer-Rao bound beside its figures
// (app/processing/crb.h ValidationCrb computes them from the virtual rig's physics; on a hardware
// rig the block says why there is none).
void WriteSummaryYaml(const std::string& path, const ValidationSummary& summary,
                      const std::map<std::string, std::string>& context = {},
                      const std::map<std::string, CrbFigures>& crb = {});

}  // namespace irdist
