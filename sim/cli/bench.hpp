// mcsim bench: real-time factor of the closed-loop FOC software-in-the-loop
// run (firmware fast step + host HAL + RK4 plant), printed as JSON.
#pragma once
#include <string>
#include <vector>

namespace mcsim {
int cmd_bench(const std::vector<std::string>& args);
}
