/**
 * @file mc_param_types.h
 * @brief Types of the generated parameter table (mc_params_gen.h).
 */
#ifndef MC_PARAM_TYPES_H
#define MC_PARAM_TYPES_H

#include <stdint.h>

/* Parameter types: the CAN value is the 32 raw bits of the value. */
#define MC_PARAM_TYPE_F32 0u /**< IEEE 754 single */
#define MC_PARAM_TYPE_U32 1u /**< unsigned 32-bit */

/* Access classes. */
#define MC_PARAM_ACCESS_RUNTIME  0u /**< may change while the bridge is on */
#define MC_PARAM_ACCESS_STOPPED  1u /**< only while the bridge is off */
#define MC_PARAM_ACCESS_REBOOT   2u /**< only while off; takes effect after save + reset */
#define MC_PARAM_ACCESS_READONLY 3u /**< computed by the drive, never stored */

#define MC_PARAM_NO_FIELD 0xFFFFu /**< offset of a readonly parameter */

/** A parameter value: its type says which member. */
typedef union {
    float f;
    uint32_t u;
} mc_param_value_t;

/** One row of the parameter table. */
typedef struct {
    uint16_t id;          /**< CAN parameter id */
    uint8_t type;         /**< MC_PARAM_TYPE_* */
    uint8_t access;       /**< MC_PARAM_ACCESS_* */
    uint16_t offset;      /**< byte offset in mc_params_t, or MC_PARAM_NO_FIELD */
    mc_param_value_t min; /**< inclusive */
    mc_param_value_t max; /**< inclusive */
    mc_param_value_t def; /**< default */
} mc_param_info_t;

#endif /* MC_PARAM_TYPES_H */
