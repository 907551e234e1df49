#include "estimator/normal_table.h"

#include <array>
#include <cmath>

namespace irdist {
namespace {

using Nodes = std::array<NormalValues, kNormalTableNodes>;

Nodes BuildNodes() {
  Nodes nodes{};
  for (int i = 0; i < kNormalTableNodes; ++i) {
    const double x = -kNormalTableReach + static_cast<double>(i) / kNormalTableNodesPerUnit;
    nodes[i].cdf = 0.5 * std::erfc(-x * 0.70710678118654752440);
    nodes[i].pdf = std::exp(-0.5 * x * x) * 0.39894228040143267794;
  }
  return nodes;
}

const Nodes kNodes = BuildNodes();

}  // namespace

const NormalValues* const kNormalTable = kNodes.data();

}  // namespace irdist
