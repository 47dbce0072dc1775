/* The pipeline's outputs as LCM messages (lcm_out.h). */
#include "lcm_out.h"

#include <string.h>

_Static_assert(LOADID_LCM_NAME_MAX == LOADID_LOAD_NAME_MAX, "load_name fits both ways");

int loadid_lcm_out_estimate(const loadid_pipeline_estimate_t *e, uint8_t *buf, size_t cap) {
    loadid_lcm_estimate_t m;
    memset(&m, 0, sizeof m);
    m.utime = e->utime;
    m.samples = e->samples;
    m.method = (int8_t)e->method;
    m.state = (int8_t)e->state;
    memcpy(m.load_name, e->load_name, sizeof m.load_name);
    m.load_name[sizeof m.load_name - 1] = 0;
    memcpy(m.phi, e->phi, sizeof m.phi);
    memcpy(m.offset, e->offset, sizeof m.offset);
    m.mass = e->mass;
    memcpy(m.com, e->com, sizeof m.com);
    memcpy(m.inertia_com, e->inertia_com, sizeof m.inertia_com);
    m.condition_number = e->condition_number;
    m.sigma_min = e->sigma_min;
    m.physically_consistent = (int8_t)e->physically_consistent;
    return loadid_lcm_encode_estimate(&m, buf, cap);
}

int loadid_lcm_out_load_model(const loadid_pipeline_estimate_t *e, uint8_t *buf, size_t cap) {
    loadid_lcm_load_model_t m;
    memset(&m, 0, sizeof m);
    m.utime = e->utime;
    m.method = (int8_t)e->method;
    memcpy(m.load_name, e->load_name, sizeof m.load_name);
    m.load_name[sizeof m.load_name - 1] = 0;
    m.identified = (int8_t)e->identified;
    m.projected = (int8_t)e->projected;
    memcpy(m.phi, e->model_phi, sizeof m.phi);
    memcpy(m.phi_std, e->phi_std, sizeof m.phi_std);
    m.mass = e->model_mass;
    memcpy(m.com, e->model_com, sizeof m.com);
    memcpy(m.inertia_com, e->model_inertia_com, sizeof m.inertia_com);
    return loadid_lcm_encode_load_model(&m, buf, cap);
}

int loadid_lcm_out_wrench(int64_t utime, const double force[3], const double torque[3],
                          uint8_t *buf, size_t cap) {
    loadid_lcm_wrench_t m;
    m.utime = utime;
    memcpy(m.force, force, sizeof m.force);
    memcpy(m.torque, torque, sizeof m.torque);
    return loadid_lcm_encode_wrench(&m, buf, cap);
}
