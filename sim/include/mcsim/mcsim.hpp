// mcsim/mcsim.hpp: umbrella header of the plant simulator library (mc_sim).
#ifndef MCSIM_MCSIM_HPP
#define MCSIM_MCSIM_HPP

#include "mcsim/cogging.hpp"
#include "mcsim/dc_link.hpp"
#include "mcsim/frames.hpp"
#include "mcsim/hall.hpp"
#include "mcsim/integrator.hpp"
#include "mcsim/inverter.hpp"
#include "mcsim/load_torque.hpp"
#include "mcsim/pmsm_ab.hpp"
#include "mcsim/pmsm_dq.hpp"
#include "mcsim/pmsm_normalised.hpp"
#include "mcsim/pmsm_params.hpp"
#include "mcsim/pmsm_power_stage.hpp"
#include "mcsim/pmsm_rotor_frame.hpp"
#include "mcsim/sensors.hpp"
#include "mcsim/spi_encoders.hpp"
#include "mcsim/status.hpp"
#include "mcsim/stepper_2ph.hpp"
#include "mcsim/stepper_common_leg_stage.hpp"
#include "mcsim/stepper_power_stage.hpp"
#include "mcsim/thermal.hpp"

#endif  // MCSIM_MCSIM_HPP
