/* loadid estimation core: the whole C API. */
#ifndef LOADID_CORE_H
#define LOADID_CORE_H

#include "loadid/types.h"
#include "loadid/regressor.h"
#include "loadid/estimator.h"
#include "loadid/inertia.h"
#include "loadid/load_model.h"
#include "loadid/chain.h"
#include "loadid/kinematics.h"
#include "loadid/joint_filter.h"
#include "loadid/signals.h"

#endif /* LOADID_CORE_H */
