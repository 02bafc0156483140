// smarticle_chrono: run one smarticle scene in Project Chrono (the paper authors' engine) and record it.
//
//   smarticle_chrono SCENE.json RECORDING.bin
//
// The scene is what smarticle_sim.chrono_reference writes (robots with their link sizes, masses and
// inertias, poses, arm angles and square-gait settings; the contact material; step, duration, record
// interval). The recording is raw little-endian float64 rows, one per sample (the first at t = 0):
//
//   t, then per robot k: x, y, z (m), qx, qy, qz, qw (body orientation), alpha1, alpha2 (rad),
//   then N x N flags (1: robots i and j overlapped at some step since the sample before).
//
// On success a one-line JSON summary goes to stdout (samples, trouble, peak overlap and tilt, Chrono's
// version, wall time); on bad input a one-line message goes to stderr and the exit code is 2.
//
// The model follows the authors' published pair code: every link a box with its own mass and inertia,
// smooth (SMC, Hertzian) or non-smooth (NSC) contact from the material's Young's modulus, Poisson ratio,
// friction and restitution, the arms on rigid speed motors (ChLinkMotorRotationSpeed) whose speed is a
// function of time alone: the square gait's open-loop stroke, the servo's top speed while the arm moves.
// The plate is a fixed box whose top face is z = 0. Units SI; x, y in the plate, z up.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "chrono/ChVersion.h"
#include "chrono/collision/ChCollisionShapeBox.h"
#include "chrono/collision/ChCollisionSystem.h"
#include "chrono/functions/ChFunctionConst.h"
#include "chrono/physics/ChBody.h"
#include "chrono/physics/ChContactContainer.h"
#include "chrono/physics/ChContactMaterialNSC.h"
#include "chrono/physics/ChContactMaterialSMC.h"
#include "chrono/physics/ChLinkMotorRotationSpeed.h"
#include "chrono/physics/ChSystemNSC.h"
#include "chrono/physics/ChSystemSMC.h"
#include "chrono_thirdparty/rapidjson/document.h"

using namespace chrono;

namespace {

struct BadScene : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// ------------------------------------------------------------------ scene reading

const rapidjson::Value& member(const rapidjson::Value& obj, const char* name, const std::string& where) {
    if (!obj.IsObject() || !obj.HasMember(name))
        throw BadScene(where + ": missing '" + name + "'");
    return obj[name];
}

double number(const rapidjson::Value& obj, const char* name, const std::string& where) {
    const auto& v = member(obj, name, where);
    if (!v.IsNumber() || !std::isfinite(v.GetDouble()))
        throw BadScene(where + "." + name + ": expected a finite number");
    return v.GetDouble();
}

double positive(const rapidjson::Value& obj, const char* name, const std::string& where) {
    double v = number(obj, name, where);
    if (v <= 0.0)
        throw BadScene(where + "." + name + ": expected a number > 0");
    return v;
}

ChVector3d vector3(const rapidjson::Value& obj, const char* name, const std::string& where, bool strictly_positive) {
    const auto& v = member(obj, name, where);
    if (!v.IsArray() || v.Size() != 3)
        throw BadScene(where + "." + name + ": expected three numbers");
    double x[3];
    for (rapidjson::SizeType i = 0; i < 3; ++i) {
        if (!v[i].IsNumber() || !std::isfinite(v[i].GetDouble()) || (strictly_positive && v[i].GetDouble() <= 0.0))
            throw BadScene(where + "." + name + ": expected three " +
                           (strictly_positive ? "positive" : "finite") + " numbers");
        x[i] = v[i].GetDouble();
    }
    return ChVector3d(x[0], x[1], x[2]);
}

std::string text(const rapidjson::Value& obj, const char* name, const std::string& where) {
    const auto& v = member(obj, name, where);
    if (!v.IsString())
        throw BadScene(where + "." + name + ": expected a string");
    return v.GetString();
}

struct Link {
    ChVector3d size;     // box edges (m): body x along the body, y its normal; arm x from joint to tip
    double mass;         // kg
    ChVector3d inertia;  // principal moments about the link's centre (kg m^2), box axes
};

struct Gait {
    double alpha_max, period, servo_speed, phase;  // rad, s, rad/s, periods in [0, 1)
};

struct Robot {
    double x, y, heading, alpha1, alpha2;  // m, m, rad (the body normal), rad, rad
    Link body, arm;                        // both arms share sizes; masses / inertias may differ
    double arm_mass[2];
    ChVector3d arm_inertia[2];
    double arm_z;                          // arm centre above the body centre (m)
    bool has_gait;
    Gait gait;
    bool fixed;                            // body held in place (its arms still move)
};

struct Material {
    double youngs, poisson, friction, restitution;
};

struct Scene {
    std::string contact;          // "smc" or "nsc"
    std::string collision;        // "multicore" (Chrono's own) or "bullet"
    double step, duration, record_interval, gravity, envelope, plate_size, plate_thickness, max_tilt;
    Material robot_material, plate_material;
    std::vector<Robot> robots;
};

Link read_link(const rapidjson::Value& v, const std::string& where) {
    Link link;
    link.size = vector3(v, "size", where, true);
    link.mass = positive(v, "mass", where);
    link.inertia = vector3(v, "inertia", where, true);
    return link;
}

Material read_material(const rapidjson::Value& v, const std::string& where) {
    Material m;
    m.youngs = positive(v, "youngs_modulus", where);
    m.poisson = number(v, "poisson_ratio", where);
    m.friction = number(v, "friction", where);
    m.restitution = number(v, "restitution", where);
    if (m.poisson < 0.0 || m.poisson >= 0.5)
        throw BadScene(where + ".poisson_ratio: expected a number in [0, 0.5)");
    if (m.friction < 0.0)
        throw BadScene(where + ".friction: expected a number >= 0");
    if (m.restitution < 0.0 || m.restitution > 1.0)
        throw BadScene(where + ".restitution: expected a number in [0, 1]");
    return m;
}

Scene read_scene(const std::string& path) {
    std::ifstream in(path);
    if (!in)
        throw BadScene("cannot read the scene file " + path);
    std::stringstream buffer;
    buffer << in.rdbuf();
    rapidjson::Document doc;
    doc.Parse(buffer.str().c_str());
    if (doc.HasParseError() || !doc.IsObject())
        throw BadScene(path + " is not a JSON object");
    Scene s;
    const std::string top = "scene";
    if (!doc.HasMember("format") || !doc["format"].IsInt() || doc["format"].GetInt() != 1)
        throw BadScene("scene.format: this driver reads format 1");
    s.contact = text(doc, "contact", top);
    if (s.contact != "smc" && s.contact != "nsc")
        throw BadScene("scene.contact: expected 'smc' or 'nsc'");
    s.collision = text(doc, "collision_system", top);
    if (s.collision != "multicore" && s.collision != "bullet")
        throw BadScene("scene.collision_system: expected 'multicore' or 'bullet'");
    s.step = positive(doc, "step", top);
    s.duration = positive(doc, "duration", top);
    s.record_interval = positive(doc, "record_interval", top);
    double steps_per_record = s.record_interval / s.step;
    if (std::fabs(steps_per_record - std::round(steps_per_record)) > 1e-6 * steps_per_record)
        throw BadScene("scene.record_interval: not a whole number of steps");
    s.gravity = number(doc, "gravity", top);
    s.envelope = positive(doc, "collision_envelope", top);
    s.plate_size = positive(doc, "plate_size", top);
    s.plate_thickness = positive(doc, "plate_thickness", top);
    s.max_tilt = positive(doc, "max_tilt", top);
    s.robot_material = read_material(member(doc, "robot_material", top), "scene.robot_material");
    s.plate_material = read_material(member(doc, "plate_material", top), "scene.plate_material");
    const auto& robots = member(doc, "robots", top);
    if (!robots.IsArray() || robots.Size() < 1)
        throw BadScene("scene.robots: expected a list of at least one robot");
    if (robots.Size() > 15)
        throw BadScene("scene.robots: at most 15 robots (one collision family each)");
    for (rapidjson::SizeType k = 0; k < robots.Size(); ++k) {
        const std::string where = "scene.robots[" + std::to_string(k) + "]";
        const auto& r = robots[k];
        Robot robot;
        robot.x = number(r, "x", where);
        robot.y = number(r, "y", where);
        robot.heading = number(r, "heading", where);
        robot.alpha1 = number(r, "alpha1", where);
        robot.alpha2 = number(r, "alpha2", where);
        robot.body = read_link(member(r, "body", where), where + ".body");
        const auto& arms = member(r, "arms", where);
        if (!arms.IsArray() || arms.Size() != 2)
            throw BadScene(where + ".arms: expected two arms");
        for (rapidjson::SizeType j = 0; j < 2; ++j) {
            Link arm = read_link(arms[j], where + ".arms[" + std::to_string(j) + "]");
            if (j == 0)
                robot.arm = arm;
            else if ((arm.size - robot.arm.size).Length() > 1e-12)
                throw BadScene(where + ".arms: the two arms must have the same size");
            robot.arm_mass[j] = arm.mass;
            robot.arm_inertia[j] = arm.inertia;
        }
        robot.arm_z = number(r, "arm_z", where);
        robot.fixed = r.HasMember("fixed") && r["fixed"].IsBool() && r["fixed"].GetBool();
        robot.has_gait = r.HasMember("gait") && !r["gait"].IsNull();
        if (robot.has_gait) {
            const auto& g = r["gait"];
            const std::string gw = where + ".gait";
            robot.gait = {positive(g, "alpha_max", gw), positive(g, "period", gw), positive(g, "servo_speed", gw),
                          number(g, "phase", gw)};
            if (robot.gait.phase < 0.0 || robot.gait.phase >= 1.0)
                throw BadScene(gw + ".phase: expected a fraction of a period in [0, 1)");
        }
        s.robots.push_back(robot);
    }
    return s;
}

// ------------------------------------------------------------------ the gait as a motor speed

// Arm moved in each quarter of the period and the corner signs (alpha1, alpha2) in traversal order:
// the project's square gait (smarticle_common.gait).
constexpr int kMovingArm[4] = {0, 1, 0, 1};
constexpr int kCornerSigns[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
// A time on a quarter boundary up to rounding belongs to the new quarter (the gait core's TIME_EPS).
constexpr double kTimeEps = 1e-9;

// d alpha / dt of one arm of the open-loop square gait at time t (s from the synchronised start): the servo's
// top speed toward the next corner from the start of the arm's quarter until it arrives, 0 otherwise.
class GaitSpeed : public ChFunction {
  public:
    GaitSpeed(const Gait& gait, int arm) : gait_(gait), arm_(arm) {}
    GaitSpeed* Clone() const override { return new GaitSpeed(*this); }
    double GetVal(double t) const override {
        double tau = (std::max(t, 0.0) + kTimeEps) / gait_.period + gait_.phase;
        double count = std::floor(4.0 * tau);
        int quarter = static_cast<int>(std::fmod(count, 4.0));
        if (kMovingArm[quarter] != arm_)
            return 0.0;
        int from = kCornerSigns[quarter][arm_], to = kCornerSigns[(quarter + 1) % 4][arm_];
        double elapsed = (tau - count / 4.0) * gait_.period;
        double stroke = std::fabs(to - from) * gait_.alpha_max / gait_.servo_speed;
        return elapsed < stroke ? (to > from ? 1.0 : -1.0) * gait_.servo_speed : 0.0;
    }

  private:
    Gait gait_;
    int arm_;
};

// ------------------------------------------------------------------ building the world

std::shared_ptr<ChContactMaterial> make_material(const Material& m, bool smc) {
    if (smc) {
        auto mat = chrono_types::make_shared<ChContactMaterialSMC>();
        mat->SetYoungModulus(static_cast<float>(m.youngs));
        mat->SetPoissonRatio(static_cast<float>(m.poisson));
        mat->SetFriction(static_cast<float>(m.friction));
        mat->SetRestitution(static_cast<float>(m.restitution));
        return mat;
    }
    auto mat = chrono_types::make_shared<ChContactMaterialNSC>();
    mat->SetFriction(static_cast<float>(m.friction));
    mat->SetRestitution(static_cast<float>(m.restitution));
    return mat;
}

std::shared_ptr<ChBody> make_box(const ChVector3d& size, double mass, const ChVector3d& inertia,
                                 std::shared_ptr<ChContactMaterial> material, int family) {
    auto body = chrono_types::make_shared<ChBody>();
    body->SetMass(mass);
    body->SetInertiaXX(inertia);
    body->AddCollisionShape(chrono_types::make_shared<ChCollisionShapeBox>(material, size.x(), size.y(), size.z()));
    body->EnableCollision(true);
    body->GetCollisionModel()->SetFamily(family);
    body->GetCollisionModel()->DisallowCollisionsWith(family);  // a robot's links never touch each other
    return body;
}

struct RobotBodies {
    std::shared_ptr<ChBody> body, arm[2];
    std::shared_ptr<ChLinkMotorRotationSpeed> motor[2];
};

// Robot k in family k + 1 (the plate keeps family 0). Body frame: x from joint 1 to joint 2, y the normal,
// z up; arm 1 hangs on the -x end and arm 2 on the +x end; alpha > 0 turns an arm's tip toward +y.
RobotBodies add_robot(ChSystem& sys, const Robot& r, int family, std::shared_ptr<ChContactMaterial> material) {
    RobotBodies out;
    const double w = r.body.size.x(), h = r.body.size.z(), l = r.arm.size.x();
    const ChQuaternion<> yaw = QuatFromAngleZ(r.heading - CH_PI_2);  // body x axis from its normal
    const ChVector3d centre(r.x, r.y, h / 2.0);
    out.body = make_box(r.body.size, r.body.mass, r.body.inertia, material, family);
    out.body->SetPos(centre);
    out.body->SetRot(yaw);
    out.body->SetFixed(r.fixed);
    sys.AddBody(out.body);
    const double alpha[2] = {r.alpha1, r.alpha2};
    for (int j = 0; j < 2; ++j) {
        const double side = j == 0 ? -1.0 : 1.0;
        // the arm's own x axis runs from its joint to its tip: angle pi - alpha1 (arm 1), alpha2 (arm 2)
        const double angle = j == 0 ? CH_PI - alpha[0] : alpha[1];
        const ChVector3d joint(side * w / 2.0, 0.0, r.arm_z);
        const ChVector3d arm_centre = joint + ChVector3d(std::cos(angle), std::sin(angle), 0.0) * (l / 2.0);
        auto arm = make_box(r.arm.size, r.arm_mass[j], r.arm_inertia[j], material, family);
        arm->SetPos(centre + yaw.Rotate(arm_centre));
        arm->SetRot(yaw * QuatFromAngleZ(angle));
        sys.AddBody(arm);
        out.arm[j] = arm;
        auto motor = chrono_types::make_shared<ChLinkMotorRotationSpeed>();
        // the motor turns the arm about the frame's z axis: -z of the body for arm 1, +z for arm 2, so a
        // positive speed raises alpha on both sides
        const ChQuaternion<> axis = j == 0 ? yaw * QuatFromAngleX(CH_PI) : yaw;
        motor->Initialize(arm, out.body, ChFrame<>(centre + yaw.Rotate(joint), axis));
        if (r.has_gait)
            motor->SetSpeedFunction(chrono_types::make_shared<GaitSpeed>(r.gait, j));
        else
            motor->SetSpeedFunction(chrono_types::make_shared<ChFunctionConst>(0.0));
        sys.AddLink(motor);
        out.motor[j] = motor;
    }
    return out;
}

// The arm angles (rad) of a robot from its links' orientations, in the body frame.
void arm_angles(const RobotBodies& rb, double out[2]) {
    for (int j = 0; j < 2; ++j) {
        ChVector3d dir = rb.body->GetRot().RotateBack(rb.arm[j]->GetRot().GetAxisX());
        out[j] = j == 0 ? std::atan2(dir.y(), -dir.x()) : std::atan2(dir.y(), dir.x());
    }
}

// Robot-robot overlaps since the last reset: which pairs, and the deepest (m).
class OverlapReporter : public ChContactContainer::ReportContactCallback {
  public:
    OverlapReporter(const std::unordered_map<const ChContactable*, int>& owner, int n)
        : owner_(owner), n_(n), touched_(static_cast<size_t>(n) * n, 0) {}
    bool OnReportContact(const ChVector3d&, const ChVector3d&, const ChMatrix33<>&, double distance, double,
                         const ChVector3d&, const ChVector3d&, ChContactable* a, ChContactable* b, int) override {
        if (distance >= 0.0)
            return true;
        auto ia = owner_.find(a), ib = owner_.find(b);
        if (ia == owner_.end() || ib == owner_.end() || ia->second == ib->second)
            return true;
        touched_[ia->second * n_ + ib->second] = touched_[ib->second * n_ + ia->second] = 1;
        peak_ = std::max(peak_, -distance);
        return true;
    }
    std::vector<char>& touched() { return touched_; }
    double peak() const { return peak_; }

  private:
    const std::unordered_map<const ChContactable*, int>& owner_;
    int n_;
    std::vector<char> touched_;
    double peak_ = 0.0;
};

std::string json_escape(const std::string& s) {
    std::string out;
    for (char c : s) {
        if (c == '"' || c == '\\')
            out += '\\';
        out += c;
    }
    return out;
}

int run(const Scene& s, const std::string& out_path) {
    const bool smc = s.contact == "smc";
    ChCollisionModel::SetDefaultSuggestedEnvelope(s.envelope);
    ChCollisionModel::SetDefaultSuggestedMargin(std::min(s.envelope, 0.0005));
    std::unique_ptr<ChSystem> sys;
    if (smc) {
        auto smc_sys = new ChSystemSMC();
        smc_sys->SetContactForceModel(ChSystemSMC::Hertz);
        smc_sys->UseMaterialProperties(true);
        sys.reset(smc_sys);
    } else {
        sys.reset(new ChSystemNSC());
    }
    sys->SetCollisionSystemType(s.collision == "multicore" ? ChCollisionSystem::Type::MULTICORE
                                                           : ChCollisionSystem::Type::BULLET);
    sys->SetGravitationalAcceleration(ChVector3d(0.0, 0.0, -s.gravity));
    sys->SetNumThreads(1);

    auto plate = chrono_types::make_shared<ChBody>();
    plate->SetFixed(true);
    plate->SetPos(ChVector3d(0.0, 0.0, -s.plate_thickness / 2.0));
    plate->AddCollisionShape(chrono_types::make_shared<ChCollisionShapeBox>(
        make_material(s.plate_material, smc), s.plate_size, s.plate_size, s.plate_thickness));
    plate->EnableCollision(true);
    sys->AddBody(plate);

    const int n = static_cast<int>(s.robots.size());
    auto robot_material = make_material(s.robot_material, smc);
    std::vector<RobotBodies> robots;
    std::unordered_map<const ChContactable*, int> owner;
    for (int k = 0; k < n; ++k) {
        robots.push_back(add_robot(*sys, s.robots[k], k + 1, robot_material));
        owner[robots.back().body.get()] = k;
        owner[robots.back().arm[0].get()] = k;
        owner[robots.back().arm[1].get()] = k;
    }
    auto reporter = chrono_types::make_shared<OverlapReporter>(owner, n);

    std::ofstream out(out_path, std::ios::binary | std::ios::trunc);
    if (!out)
        throw BadScene("cannot write the recording " + out_path);
    const long steps_per_record = std::lround(s.record_interval / s.step);
    const long samples = static_cast<long>(std::floor(s.duration / s.record_interval + 1e-9)) + 1;
    const size_t width = 1 + 9 * static_cast<size_t>(n) + static_cast<size_t>(n) * n;
    std::vector<double> row(width);
    std::string trouble;
    double peak_tilt = 0.0;
    long taken = 0, steps = 0;
    const auto wall_start = std::chrono::steady_clock::now();

    for (long sample = 0; sample < samples; ++sample) {
        if (sample > 0) {
            for (long i = 0; i < steps_per_record; ++i) {
                sys->DoStepDynamics(s.step);
                ++steps;
                sys->GetContactContainer()->ReportAllContacts(reporter);
            }
        }
        size_t c = 0;
        row[c++] = sys->GetChTime();
        bool finite = true;
        for (int k = 0; k < n; ++k) {
            const auto& body = robots[k].body;
            const ChVector3d p = body->GetPos();
            const ChQuaternion<> q = body->GetRot();
            double alpha[2];
            arm_angles(robots[k], alpha);
            const double values[9] = {p.x(), p.y(), p.z(), q.e1(), q.e2(), q.e3(), q.e0(), alpha[0], alpha[1]};
            for (double v : values) {
                finite = finite && std::isfinite(v);
                row[c++] = v;
            }
            const double tilt = std::acos(std::clamp(q.GetAxisZ().z(), -1.0, 1.0));
            peak_tilt = std::max(peak_tilt, tilt);
            if (trouble.empty() && tilt > s.max_tilt) {
                std::ostringstream msg;
                msg << "robot " << k << " tipped " << tilt * 180.0 / CH_PI << " deg at t = " << sys->GetChTime()
                    << " s (Chrono)";
                trouble = msg.str();
            }
            if (trouble.empty() && (std::fabs(p.x()) > s.plate_size / 2.0 || std::fabs(p.y()) > s.plate_size / 2.0)) {
                std::ostringstream msg;
                msg << "robot " << k << " left the plate at t = " << sys->GetChTime() << " s (Chrono)";
                trouble = msg.str();
            }
        }
        auto& touched = reporter->touched();
        for (char t : touched)
            row[c++] = t ? 1.0 : 0.0;
        std::fill(touched.begin(), touched.end(), 0);
        out.write(reinterpret_cast<const char*>(row.data()), static_cast<std::streamsize>(width * sizeof(double)));
        ++taken;
        if (!finite && trouble.empty()) {
            std::ostringstream msg;
            msg << "non-finite state at t = " << sys->GetChTime() << " s (Chrono)";
            trouble = msg.str();
        }
        if (!trouble.empty())
            break;
    }
    out.close();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    std::cout << "{\"samples\": " << taken << ", \"robots\": " << n << ", \"columns\": " << width
              << ", \"steps\": " << steps << ", \"trouble\": \"" << json_escape(trouble)
              << "\", \"peak_overlap_m\": " << reporter->peak() << ", \"peak_tilt_rad\": " << peak_tilt
              << ", \"chrono_version\": \"" << CHRONO_VERSION << "\", \"wall_time_s\": " << wall << "}"
              << std::endl;
    return 0;
}

}  // namespace

int main(int argc, char* argv[]) {
    if (argc != 3) {
        std::cerr << "usage: smarticle_chrono SCENE.json RECORDING.bin" << std::endl;
        return 2;
    }
    try {
        return run(read_scene(argv[1]), argv[2]);
    } catch (const BadScene& e) {
        std::cerr << "smarticle_chrono: " << e.what() << std::endl;
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "smarticle_chrono: Chrono failed: " << e.what() << std::endl;
        return 1;
    }
}
