// loadid/urdf.h: the chain from base_link to sensor_link of a URDF, read
// with urdfdom and folded into loadid_chain_t (fixed joints merged into the
// next transform). Host side, start-up only: files, XML, heap, exceptions.
#include "loadid/urdf.h"

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

namespace {

// Collects urdfdom's error messages (it logs them through console_bridge
// and returns only a null model) so the caller gets the cause.
class Capture : public console_bridge::OutputHandler {
  public:
    std::string first_error;
    void log(const std::string &text, console_bridge::LogLevel level, const char *, int) override {
        if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error.empty())
            first_error = text;
    }
};

struct Fail {
    int code;
    std::string why;
};

// A rigid transform as (R, p): x_parent = R x_child + p.
struct Transform {
    double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double p[3] = {0, 0, 0};
};

Transform from_pose(const urdf::Pose &pose) {
    double x = pose.rotation.x, y = pose.rotation.y, z = pose.rotation.z, w = pose.rotation.w;
    double n = x * x + y * y + z * z + w * w;
    if (!(n > 0) || !std::isfinite(n)) throw Fail{LOADID_E_MODEL, "a joint origin is not finite"};
    double s = 2.0 / n; // the unit-quaternion rotation matrix, normalised
    Transform t;
    t.r[0] = 1 - s * (y * y + z * z);
    t.r[1] = s * (x * y - z * w);
    t.r[2] = s * (x * z + y * w);
    t.r[3] = s * (x * y + z * w);
    t.r[4] = 1 - s * (x * x + z * z);
    t.r[5] = s * (y * z - x * w);
    t.r[6] = s * (x * z - y * w);
    t.r[7] = s * (y * z + x * w);
    t.r[8] = 1 - s * (x * x + y * y);
    t.p[0] = pose.position.x;
    t.p[1] = pose.position.y;
    t.p[2] = pose.position.z;
    return t;
}

// a * b: first a, then b in a's child frame.
Transform compose(const Transform &a, const Transform &b) {
    Transform t;
    for (int i = 0; i < 3; ++i) {
        t.p[i] = a.p[i];
        for (int j = 0; j < 3; ++j) {
            t.p[i] += a.r[3 * i + j] * b.p[j];
            double v = 0;
            for (int k = 0; k < 3; ++k) v += a.r[3 * i + k] * b.r[3 * k + j];
            t.r[3 * i + j] = v;
        }
    }
    return t;
}

void copy_name(char *dst, const std::string &src, const char *what) {
    if (src.size() >= LOADID_NAME_MAX)
        throw Fail{LOADID_E_MODEL, std::string(what) + " name '" + src + "' is longer than " +
                                       std::to_string(LOADID_NAME_MAX - 1) + " characters"};
    std::memcpy(dst, src.c_str(), src.size() + 1);
}

const char *type_name(int type) {
    switch (type) {
        case urdf::Joint::FLOATING:
            return "floating";
        case urdf::Joint::PLANAR:
            return "planar";
        default:
            return "unknown-type";
    }
}

void fill_joint(const urdf::Joint &j, const Transform &origin, loadid_joint_desc_t &d) {
    copy_name(d.name, j.name, "joint");
    d.type = j.type == urdf::Joint::PRISMATIC ? LOADID_JOINT_PRISMATIC : LOADID_JOINT_REVOLUTE;
    std::memcpy(d.origin_xyz, origin.p, sizeof d.origin_xyz);
    std::memcpy(d.origin_rot, origin.r, sizeof d.origin_rot);
    double a[3] = {j.axis.x, j.axis.y, j.axis.z};
    double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(n > 1e-12) || !std::isfinite(n))
        throw Fail{LOADID_E_MODEL, "joint '" + j.name + "' has a zero or non-finite axis"};
    for (int i = 0; i < 3; ++i) d.axis[i] = a[i] / n; // URDF asks for unit axes; be lenient
    const double inf = std::numeric_limits<double>::infinity();
    d.lower = -inf;
    d.upper = inf;
    d.velocity = inf;
    if (j.limits) {
        if (j.type != urdf::Joint::CONTINUOUS) {
            d.lower = j.limits->lower;
            d.upper = j.limits->upper;
        }
        if (j.limits->velocity > 0) d.velocity = j.limits->velocity; // 0: not given
        if (std::isnan(d.lower) || std::isnan(d.upper) || !(d.lower <= d.upper))
            throw Fail{LOADID_E_MODEL, "joint '" + j.name + "' has limits lower > upper"};
    }
}

void build_chain(const urdf::ModelInterface &model, const char *base, const char *sensor,
                 loadid_chain_t &chain) {
    urdf::LinkConstSharedPtr tip = model.getLink(sensor);
    if (!tip)
        throw Fail{LOADID_E_MODEL,
                   std::string("no link named '") + sensor + "' (robot.sensor_link)"};
    if (!model.getLink(base))
        throw Fail{LOADID_E_MODEL, std::string("no link named '") + base + "' (robot.base_link)"};
    // urdfdom 3.0 keeps only the last of two parents of a link, so a loop
    // closed by a second joint onto a link would otherwise look like a tree
    // (and the walk below could go round it for ever).
    std::map<std::string, std::string> parent_of; // child link -> joint
    for (const auto &entry : model.joints_) {
        const urdf::Joint &j = *entry.second;
        auto seen = parent_of.emplace(j.child_link_name, j.name);
        if (!seen.second)
            throw Fail{LOADID_E_MODEL, "link '" + j.child_link_name +
                                           "' has two parents (joints '" + seen.first->second +
                                           "' and '" + j.name + "'): a kinematic loop, not a tree"};
    }
    // Walk up from the sensor; the joints come out in sensor-to-base order.
    std::vector<urdf::JointConstSharedPtr> path;
    for (urdf::LinkConstSharedPtr link = tip; link->name != base; link = link->getParent()) {
        if (!link->parent_joint || !link->getParent() || path.size() > model.links_.size())
            throw Fail{LOADID_E_MODEL,
                       std::string("link '") + base + "' is not an ancestor of '" + sensor + "'"};
        path.push_back(link->parent_joint);
    }
    std::memset(&chain, 0, sizeof chain);
    copy_name(chain.base_link, base, "link");
    copy_name(chain.sensor_link, sensor, "link");
    Transform pending; // fixed joints so far, folded into the next transform
    int n = 0;
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
        const urdf::Joint &j = **it;
        pending = compose(pending, from_pose(j.parent_to_joint_origin_transform));
        switch (j.type) {
            case urdf::Joint::FIXED:
                continue;
            case urdf::Joint::REVOLUTE:
            case urdf::Joint::CONTINUOUS:
            case urdf::Joint::PRISMATIC:
                break;
            default:
                throw Fail{LOADID_E_MODEL, "joint '" + j.name + "' on the chain is " +
                                               type_name(j.type) +
                                               " (only revolute, continuous, prismatic, fixed)"};
        }
        if (j.mimic)
            throw Fail{LOADID_E_MODEL, "joint '" + j.name + "' is a mimic joint (not supported)"};
        if (n == LOADID_MAX_JOINTS)
            throw Fail{LOADID_E_MODEL, "more than " + std::to_string(LOADID_MAX_JOINTS) +
                                           " movable joints on the chain"};
        fill_joint(j, pending, chain.joints[n++]);
        pending = Transform();
    }
    if (n == 0)
        throw Fail{LOADID_E_MODEL,
                   std::string("no movable joint between '") + base + "' and '" + sensor + "'"};
    chain.num_joints = n;
    std::memcpy(chain.tip_xyz, pending.p, sizeof chain.tip_xyz);
    std::memcpy(chain.tip_rot, pending.r, sizeof chain.tip_rot);
    if (loadid_chain_check(&chain) != 0)
        throw Fail{LOADID_E_MODEL, "a number on the chain is not finite"};
}

// urdfdom's links own their children (Link::child_links), so a joint graph
// with a cycle, which build_chain refuses as a loop, makes links own each
// other and the model is never freed. Cleared on every way out.
struct ReleaseLinks {
    urdf::ModelInterfaceSharedPtr &model;
    ~ReleaseLinks() {
        if (!model) return;
        for (auto &entry : model->links_)
            if (entry.second) entry.second->clear();
    }
};

// One line, as the programs print it: urdfdom's messages quote the
// offending text, and names in the file may hold any character, so control
// characters (a newline, a tab) become '?', as in the YAML reader's.
void report(char *err, size_t errlen, const char *name, const std::string &why) {
    if (!err || errlen == 0) return;
    std::snprintf(err, errlen, "%s: %s", name, why.c_str());
    for (char *c = err; *c; ++c)
        if (static_cast<unsigned char>(*c) < 0x20 || *c == 0x7f) *c = '?';
}

} // namespace

extern "C" int loadid_urdf_load_string(const char *xml, const char *name, const char *base_link,
                                       const char *sensor_link, loadid_chain_t *chain, char *err,
                                       size_t errlen) {
    if (!name) name = "URDF";
    if (!xml || !base_link || !sensor_link || !chain) {
        report(err, errlen, name, "missing argument");
        return -EINVAL;
    }
    Capture capture;
    console_bridge::OutputHandler *previous = console_bridge::getOutputHandler();
    console_bridge::useOutputHandler(&capture);
    int rc = 0;
    try {
        // TinyXML 2.6.2 (urdfdom's parser on Debian 12) steps over a whole
        // UTF-8 sequence by its lead byte (TiXmlBase::GetChar returns
        // p + length), so text that ends inside one is read past its NUL,
        // into whatever memory follows. Four NULs more keep every such step
        // inside the string; they change nothing else (the text ends at
        // the first).
        std::string text(xml);
        text.append(4, '\0');
        urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(text);
        ReleaseLinks release{model};
        if (!model) {
            throw Fail{LOADID_E_MODEL, "not a valid URDF: " + (capture.first_error.empty()
                                                                   ? std::string("parse failed")
                                                                   : capture.first_error)};
        }
        build_chain(*model, base_link, sensor_link, *chain);
    } catch (const Fail &f) {
        report(err, errlen, name, f.why);
        rc = f.code;
    } catch (const std::exception &e) {
        report(err, errlen, name, std::string("not a valid URDF: ") + e.what());
        rc = LOADID_E_MODEL;
    }
    console_bridge::useOutputHandler(previous);
    return rc;
}

extern "C" int loadid_urdf_load_file(const char *path, const char *base_link,
                                     const char *sensor_link, loadid_chain_t *chain, char *err,
                                     size_t errlen) {
    if (!path) {
        report(err, errlen, "URDF", "missing path");
        return -EINVAL;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        int e = errno ? errno : ENOENT;
        report(err, errlen, path, std::string("cannot read: ") + std::strerror(e));
        return -ENOENT;
    }
    std::ostringstream text;
    text << in.rdbuf();
    return loadid_urdf_load_string(text.str().c_str(), path, base_link, sensor_link, chain, err,
                                   errlen);
}
