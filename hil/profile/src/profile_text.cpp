#include "maglev/profile/profile_text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace maglev::profile {

namespace sp = stage_profile;

namespace {

constexpr double kPi = 3.14159265358979323846;

// kernel::Axis order and names.
constexpr const char* kAxisNames[sp::kAxes] = {"x", "y", "theta_z", "z", "theta_x", "theta_y"};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> words(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> w;
  std::string x;
  while (in >> x) w.push_back(x);
  return w;
}

bool number(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  // The whole value must be the number: compared with the string's end, not
  // with the first NUL, or "200<NUL>e-6" read as 200 (found by fuzz_profile).
  if (end != s.c_str() + s.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

// One key's reader: parses the value, checks its range, stores it; returns
// "" or the reason.
using Setter = std::function<std::string(const std::string& value)>;

Setter real(double* dst, double lo, double hi) {
  return [=](const std::string& v) -> std::string {
    double x = 0;
    if (!number(v, &x)) return "not a number: '" + v + "'";
    if (!(x >= lo && x <= hi)) {
      std::ostringstream o;
      o << "out of range [" << lo << ", " << hi << "]: " << v;
      return o.str();
    }
    *dst = x;
    return "";
  };
}
Setter integer(int* dst, int lo, int hi) {
  return [=](const std::string& v) -> std::string {
    double x = 0;
    if (!number(v, &x) || x != std::floor(x)) return "not an integer: '" + v + "'";
    if (x < lo || x > hi) return "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]: " + v;
    *dst = static_cast<int>(x);
    return "";
  };
}
Setter flag(bool* dst) {
  return [=](const std::string& v) -> std::string {
    if (v == "on" || v == "true" || v == "yes" || v == "1") *dst = true;
    else if (v == "off" || v == "false" || v == "no" || v == "0") *dst = false;
    else return "expected on/off, got '" + v + "'";
    return "";
  };
}
template <class E>
Setter choice(E* dst, std::vector<std::pair<const char*, E>> options) {
  return [=](const std::string& v) -> std::string {
    std::string list;
    for (const auto& [n, e] : options) {
      if (v == n) {
        *dst = e;
        return "";
      }
      list += std::string(list.empty() ? "" : ", ") + n;
    }
    return "expected one of " + list + ", got '" + v + "'";
  };
}
Setter text(char* dst, std::size_t size) {
  return [=](const std::string& v) -> std::string {
    if (v.empty() || v.size() >= size) return "must be 1.." + std::to_string(size - 1) + " characters";
    std::memset(dst, 0, size);
    std::memcpy(dst, v.data(), v.size());
    return "";
  };
}

using Keys = std::map<std::string, Setter>;

// A filter: "KIND FREQUENCY_HZ [Q] [DEPTH_DB] [POLE_HZ]".
Setter filter(sp::Filter* dst) {
  return [=](const std::string& v) -> std::string {
    const auto w = words(v);
    if (w.empty()) return "expected KIND FREQUENCY_HZ [Q] [DEPTH_DB] [POLE_HZ]";
    sp::Filter f{};
    f.q = 0.7071;
    const std::string e = choice(&f.kind, std::vector<std::pair<const char*, sp::FilterKind>>{
                                              {"none", sp::FilterKind::kNone},
                                              {"notch", sp::FilterKind::kNotch},
                                              {"low_pass", sp::FilterKind::kLowPass},
                                              {"lead_lag", sp::FilterKind::kLeadLag},
                                              {"butterworth2", sp::FilterKind::kButterworth2}})(w[0]);
    if (!e.empty()) return e;
    double* fields[4] = {&f.frequency_Hz, &f.q, &f.depth_dB, &f.pole_Hz};
    for (std::size_t i = 1; i < w.size() && i <= 4; ++i) {
      if (!number(w[i], fields[i - 1])) return "not a number: '" + w[i] + "'";
    }
    if (w.size() > 5) return "too many values (KIND FREQUENCY_HZ [Q] [DEPTH_DB] [POLE_HZ])";
    if (f.kind != sp::FilterKind::kNone && !(f.frequency_Hz > 0.0)) return "frequency must be > 0";
    if (!(f.q > 0.0) || f.depth_dB < 0.0 || f.pole_Hz < 0.0) return "q must be > 0, depth and pole >= 0";
    *dst = f;
    return "";
  };
}

// "AT KP_SCALE KD_SCALE; AT KP_SCALE KD_SCALE; ..." with AT increasing.
Setter schedule(sp::AxisController* c) {
  return [=](const std::string& v) -> std::string {
    std::vector<sp::SchedulePoint> pts;
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ';')) {
      const auto w = words(item);
      if (w.empty()) continue;
      sp::SchedulePoint p{};
      if (w.size() != 3 || !number(w[0], &p.at) || !number(w[1], &p.kp_scale) || !number(w[2], &p.kd_scale)) {
        return "expected 'AT KP_SCALE KD_SCALE; ...', got '" + trim(item) + "'";
      }
      if (!(p.kp_scale > 0.0 && p.kd_scale > 0.0)) return "scales must be > 0";
      if (!pts.empty() && !(p.at > pts.back().at)) return "operating points must increase";
      pts.push_back(p);
    }
    if (pts.size() < 2 || pts.size() > static_cast<std::size_t>(sp::kMaxSchedulePoints)) {
      return "a schedule needs 2.." + std::to_string(sp::kMaxSchedulePoints) + " points";
    }
    c->schedule_points = static_cast<std::uint8_t>(pts.size());
    std::copy(pts.begin(), pts.end(), c->schedule);
    return "";
  };
}

Setter startup(sp::StartupStep* steps) {
  return [=](const std::string& v) -> std::string {
    const auto w = words(v);
    if (w.empty() || w.size() > static_cast<std::size_t>(sp::kMaxStartupSteps) - 1) {
      return "1.." + std::to_string(sp::kMaxStartupSteps - 1) + " steps";
    }
    for (int i = 0; i < sp::kMaxStartupSteps; ++i) steps[i] = sp::StartupStep::kEnd;
    for (std::size_t i = 0; i < w.size(); ++i) {
      const std::string e = choice(&steps[i], std::vector<std::pair<const char*, sp::StartupStep>>{
                                                  {"close_in_plane", sp::StartupStep::kCloseInPlane},
                                                  {"lift_feedforward", sp::StartupStep::kLiftFeedforward},
                                                  {"close_vertical", sp::StartupStep::kCloseVertical},
                                                  {"close_tilts", sp::StartupStep::kCloseTilts},
                                                  {"lift_off_from_dock", sp::StartupStep::kLiftOffFromDock},
                                                  {"ready", sp::StartupStep::kReady}})(w[i]);
      if (!e.empty()) return e;
    }
    if (steps[w.size() - 1] != sp::StartupStep::kReady) return "the sequence must end with 'ready'";
    return "";
  };
}

Setter travel(double* lo, double* hi) {
  return [=](const std::string& v) -> std::string {
    const auto w = words(v);
    double a = 0, b = 0;
    if (w.size() != 2 || !number(w[0], &a) || !number(w[1], &b)) return "expected MIN MAX (SI), got '" + v + "'";
    if (!(a < b)) return "MIN must be below MAX";
    *lo = a;
    *hi = b;
    return "";
  };
}

Keys stage_keys(sp::StageProfile* p, bool* family_set) {
  return {
      {"name", text(p->name, sizeof p->name)},
      {"title", text(p->title, sizeof p->title)},
      {"paper", [=](const std::string& v) {
         int x = 0;
         const std::string e = integer(&x, 0, 255)(v);
         if (e.empty()) p->paper = static_cast<std::uint8_t>(x);
         return e;
       }},
      {"servo_rate_Hz", real(&p->servo_rate_Hz, 100.0, 20000.0)},
      {"family", [=](const std::string& v) {
         *family_set = true;
         return choice(&p->family, std::vector<std::pair<const char*, sp::ActuatorFamily>>{
                                       {"halbach_lorentz", sp::ActuatorFamily::kHalbachLorentz},
                                       {"iron_core_pmlsm", sp::ActuatorFamily::kIronCorePmlsm},
                                       {"solenoid_magnet", sp::ActuatorFamily::kSolenoidMagnet}})(v);
       }},
      {"startup", startup(p->startup)},
  };
}

Keys body_keys(sp::Body* b) {
  Keys k{{"mass_kg", real(&b->mass_kg, 1e-3, 1e3)},
         {"inertia_x_kgm2", real(&b->inertia_kgm2[0], 1e-9, 1e3)},
         {"inertia_y_kgm2", real(&b->inertia_kgm2[1], 1e-9, 1e3)},
         {"inertia_z_kgm2", real(&b->inertia_kgm2[2], 1e-9, 1e3)},
         {"gravity_m_per_s2", real(&b->gravity_m_per_s2, 0.0, 20.0)}};
  for (int a = 0; a < sp::kAxes; ++a) {
    k[std::string("effective_mass_") + kAxisNames[a] + (a == 2 || a >= 4 ? "_kgm2" : "_kg")] =
        real(&b->effective_mass_kg[a], 0.0, 1e3);
  }
  return k;
}

Keys halbach_keys(sp::HalbachParameters* h) {
  return {
      {"layout", choice(&h->layout, std::vector<std::pair<const char*, sp::ForcerLayout>>{
                                        {"cross", sp::ForcerLayout::kCross},
                                        {"square", sp::ForcerLayout::kSquare},
                                        {"triangle", sp::ForcerLayout::kTriangle},
                                        {"custom", sp::ForcerLayout::kCustom}})},
      {"lever_arm_m", real(&h->lever_arm_m, 1e-3, 1.0)},
      {"triangle_alpha_rad", real(&h->triangle_alpha_rad, 0.0, kPi / 2)},
      {"pitch_m", real(&h->pitch_m, 1e-3, 1.0)},
      {"magnet_thickness_m", real(&h->magnet_thickness_m, 1e-4, 0.1)},
      {"two_b_star_N_per_A", real(&h->two_b_star_N_per_A, 1e-3, 1e3)},
      {"coil_effective_length_m", real(&h->coil_effective_length_m, 1e-3, 1.0)},
      {"coil_side_width_m", real(&h->coil_side_width_m, 1e-4, 0.1)},
      {"coil_thickness_m", real(&h->coil_thickness_m, 1e-4, 0.1)},
      {"coil_turns", integer(&h->coil_turns, 1, 100000)},
      {"rest_gap_m", real(&h->rest_gap_m, 1e-5, 0.1)},
  };
}

Keys pmlsm_keys(sp::PmlsmParameters* m) {
  return {
      {"slot_width_m", real(&m->slot_width_m, 1e-4, 0.1)},
      {"slot_pitch_m", real(&m->slot_pitch_m, 1e-4, 0.1)},
      {"pole_pitch_m", real(&m->pole_pitch_m, 1e-3, 1.0)},
      {"magnet_height_m", real(&m->magnet_height_m, 1e-4, 0.1)},
      {"coercivity_A_per_m", real(&m->coercivity_A_per_m, 1e3, 1e7)},
      {"turns_per_phase", integer(&m->turns_per_phase, 1, 100000)},
      {"magnets_per_motor", integer(&m->magnets_per_motor, 1, 100)},
      {"pole_pairs", integer(&m->pole_pairs, 1, 100)},
      {"nominal_gap_m", real(&m->nominal_gap_m, 1e-4, 0.2)},
      {"min_gap_m", real(&m->min_gap_m, 1e-4, 0.2)},
      {"max_gap_m", real(&m->max_gap_m, 1e-4, 0.2)},
      {"vertical_attraction_scale", real(&m->vertical_attraction_scale, 0.0, 10.0)},
      {"magnet_length_m", real(&m->magnet_length_m, 1e-4, 1.0)},
      {"magnet_width_m", real(&m->magnet_width_m, 1e-4, 1.0)},
      {"winding_factor", real(&m->winding_factor, 0.1, 1.0)},
      {"recoil_permeability", real(&m->recoil_permeability, 1.0, 10.0)},
      {"radius_to_movers_m", real(&m->radius_to_movers_m, 1e-3, 10.0)},
      {"guide_torsion_phi_per_s2", real(&m->guide_torsion_phi_per_s2, 0.0, 1e9)},
      {"guide_torsion_theta_per_s2", real(&m->guide_torsion_theta_per_s2, 0.0, 1e9)},
  };
}

Keys solenoid_keys(sp::SolenoidParameters* s) {
  return {
      {"magnetization_A_per_m", real(&s->magnetization_A_per_m, 1e3, 1e7)},
      {"magnet_volume_m3", real(&s->magnet_volume_m3, 1e-12, 1e-2)},
      {"solenoid_volume_m3", real(&s->solenoid_volume_m3, 1e-12, 1e-2)},
      {"length_m", real(&s->length_m, 1e-4, 1.0)},
      {"radius_r1_m", real(&s->radius_r1_m, 1e-4, 1.0)},
      {"radius_r2_m", real(&s->radius_r2_m, 1e-4, 1.0)},
      {"nominal_current_in_plane_A", real(&s->nominal_current_in_plane_A, 0.0, 100.0)},
      {"nominal_current_out_of_plane_A", real(&s->nominal_current_out_of_plane_A, 0.0, 100.0)},
      {"turns_in_plane", integer(&s->turns_in_plane, 1, 100000)},
      {"turns_out_of_plane", integer(&s->turns_out_of_plane, 1, 100000)},
      {"coil_resistance_Ohm", real(&s->coil_resistance_Ohm, 0.0, 1e4)},
      {"force_constant_in_plane_N_per_A", real(&s->force_constant_in_plane_N_per_A, 0.0, 1e3)},
      {"force_constant_out_of_plane_N_per_A", real(&s->force_constant_out_of_plane_N_per_A, 0.0, 1e3)},
  };
}

Keys limit_keys(sp::Limits* l) {
  return {
      {"peak_current_A", real(&l->peak_current_A, 1e-3, 100.0)},
      {"rms_current_A", real(&l->rms_current_A, 1e-3, 100.0)},
      {"hardware_current_A", real(&l->hardware_current_A, 1e-3, 100.0)},
      {"landing_speed_m_per_s", real(&l->landing_speed_m_per_s, 1e-6, 1.0)},
      {"nominal_height_m", real(&l->nominal_height_m, 0.0, 0.1)},
  };
}

Keys axis_keys(sp::Axis* a) {
  sp::AxisController* c = &a->controller;
  Keys k{
      {"mode", choice(&a->mode, std::vector<std::pair<const char*, sp::AxisMode>>{
                                    {"active", sp::AxisMode::kActive},
                                    {"passive", sp::AxisMode::kPassive},
                                    {"absent", sp::AxisMode::kAbsent}})},
      {"travel", travel(&a->travel_min, &a->travel_max)},
      {"max_velocity", real(&a->max_velocity, 1e-9, 100.0)},
      {"max_acceleration", real(&a->max_acceleration, 1e-9, 1e4)},
      {"open_loop_stiffness_per_s2", real(&a->open_loop_stiffness_per_s2, -1e9, 1e9)},
      {"open_loop_damping_per_s", real(&a->open_loop_damping_per_s, -1e6, 1e6)},
      {"controller", choice(&c->kind, std::vector<std::pair<const char*, sp::ControllerKind>>{
                                          {"pid2dof", sp::ControllerKind::kPid2Dof},
                                          {"internal_model", sp::ControllerKind::kInternalModel},
                                          {"state_feedback", sp::ControllerKind::kStateFeedback},
                                          {"none", sp::ControllerKind::kNone}})},
      {"kp", real(&c->kp, 0.0, 1e9)},
      {"ki", real(&c->ki, 0.0, 1e12)},
      {"kd", real(&c->kd, 0.0, 1e6)},
      {"derivative_filter_Hz", real(&c->derivative_filter_Hz, 1.0, 1e5)},
      {"setpoint_weight_p", real(&c->setpoint_weight_p, 0.0, 1.0)},
      {"effort_limit_A", real(&c->effort_limit_A, 1e-3, 100.0)},
      {"imr_omega0_rad_per_s", real(&c->imr_omega0_rad_per_s, 0.0, 1e4)},
      {"imr_bandwidth_Hz", real(&c->imr_bandwidth_Hz, 1e-3, 1e4)},
      {"imr_model_bandwidth_Hz", real(&c->imr_model_bandwidth_Hz, 1e-3, 1e4)},
      {"antiwindup_gain", real(&c->antiwindup_gain, 0.0, 1e6)},
      {"feedback_linearization", flag(&c->feedback_linearization)},
      {"lqr_weight_h", [=](const std::string& v) -> std::string {
         const auto w = words(v);
         if (w.size() != 5) return "expected 5 numbers h1..h5 (Q = h'h over [e e' xi1 xi2 xi3], R = 1)";
         for (std::size_t i = 0; i < 5; ++i) {
           if (!number(w[i], &c->lqr_weight_h[i]) || !std::isfinite(c->lqr_weight_h[i])) {
             return "not a number: '" + w[i] + "'";
           }
         }
         return "";
       }},
      {"schedule", schedule(c)},
  };
  for (int f = 0; f < sp::kMaxFilters; ++f) {
    k["filter" + std::to_string(f + 1)] = [=](const std::string& v) {
      const std::string e = filter(&c->filters[f])(v);
      if (e.empty()) c->filter_count = static_cast<std::uint8_t>(std::max<int>(c->filter_count, f + 1));
      return e;
    };
  }
  return k;
}

Keys actuator_keys(sp::Actuator* a) {
  return {{"x_m", real(&a->x_m, -10.0, 10.0)},
          {"y_m", real(&a->y_m, -10.0, 10.0)},
          {"z_m", real(&a->z_m, -10.0, 10.0)},
          {"thrust_direction_rad", real(&a->thrust_direction_rad, -2 * kPi, 2 * kPi)},
          {"phase_rad", real(&a->phase_rad, -2 * kPi, 2 * kPi)}};
}

Keys sensor_keys(sp::Sensor* s) {
  return {{"kind", choice(&s->kind, std::vector<std::pair<const char*, sp::SensorKind>>{
                                        {"interferometer", sp::SensorKind::kInterferometer},
                                        {"laser_displacement", sp::SensorKind::kLaserDisplacement},
                                        {"hall", sp::SensorKind::kHall},
                                        {"linear_encoder", sp::SensorKind::kLinearEncoder},
                                        {"psd", sp::SensorKind::kPsd}})},
          {"x_m", real(&s->x_m, -10.0, 10.0)},
          {"y_m", real(&s->y_m, -10.0, 10.0)},
          {"z_m", real(&s->z_m, -10.0, 10.0)},
          {"direction_rad", real(&s->direction_rad, -2 * kPi, 2 * kPi)},
          {"resolution", real(&s->resolution, 0.0, 1e3)},
          {"noise", real(&s->noise, 0.0, 1.0)},
          // Hall sensors only (checked at the end, when the kind is known).
          {"sensitivity_V_per_T", real(&s->sensitivity_V_per_T, 0.01, 1e4)},
          {"height_m", real(&s->height_m, 1e-5, 0.1)},
          {"axis", [=](const std::string& v) -> std::string {
             for (int a = 0; a < sp::kAxes; ++a) {
               if (v == kAxisNames[a]) {
                 s->measured_axis = static_cast<std::uint8_t>(a);
                 return "";
               }
             }
             return "expected one of x, y, theta_z, z, theta_x, theta_y";
           }}};
}

std::string key_list(const Keys& k) {
  std::string l;
  for (const auto& [n, s] : k) l += std::string(l.empty() ? "" : ", ") + n;
  return l;
}

}  // namespace

ProfileParse parse_profile(const std::string& text, const std::string& source) {
  ProfileParse r;
  sp::StageProfile& p = r.profile;
  // Every byte zero first (padding too): the record is stored and CRC-checked
  // as bytes in the firmware's profile database.
  std::memset(static_cast<void*>(&p), 0, sizeof p);
  for (auto& a : p.axis) {
    a.mode = sp::AxisMode::kAbsent;
    a.controller.kind = sp::ControllerKind::kNone;
    a.controller.setpoint_weight_p = 1.0;
    a.controller.derivative_filter_Hz = 1000.0;
    a.controller.effort_limit_A = 4.0;
  }
  p.body.gravity_m_per_s2 = 9.81;
  for (auto& sensor : p.sensors) sensor.measured_axis = sp::kGeometricSensor;
  bool family_set = false;
  int actuators_seen = 0, sensors_seen = 0;
  auto err = [&](int line, const std::string& field, const std::string& why) {
    r.errors.push_back(source + ":" + std::to_string(line) + ": " + field + ": " + why);
  };

  Keys keys;
  std::string section;
  std::map<std::string, int> seen_sections;
  std::map<std::string, int> seen_keys;
  std::set<std::string> halbach_set;  // keys given in [halbach]
  // Keys that belong to one kind of sensor or one regulator, checked at the
  // end, once the section's kind / controller is known (index: the
  // section's sensor or axis).
  struct KindKey {
    int index, line;
    std::string key;
  };
  std::vector<KindKey> hall_keys, loop_keys;
  int section_index = -1;  // the axis or sensor the current section describes
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const auto hash = raw.find('#');
    const std::string s = trim(hash == std::string::npos ? raw : raw.substr(0, hash));
    if (s.empty()) continue;
    if (s.front() == '[') {
      if (s.back() != ']') {
        err(line, "section", "expected [NAME] or [KIND ARG]");
        keys.clear();
        continue;
      }
      // One spelling per section: "[axis  x]" is "[axis x]" (the repeated-
      // section check used to compare the raw text and let it through).
      section.clear();
      for (const std::string& word : words(s.substr(1, s.size() - 2))) section += (section.empty() ? "" : " ") + word;
      seen_keys.clear();
      if (seen_sections.count(section) != 0) {
        err(line, "[" + section + "]", "repeated section (first at line " + std::to_string(seen_sections[section]) + ")");
      }
      seen_sections[section] = line;
      const auto w = words(section);
      keys.clear();
      section_index = -1;
      if (w.size() == 1 && w[0] == "stage") keys = stage_keys(&p, &family_set);
      else if (w.size() == 1 && w[0] == "body") keys = body_keys(&p.body);
      else if (w.size() == 1 && w[0] == "halbach") keys = halbach_keys(&p.halbach);
      else if (w.size() == 1 && w[0] == "pmlsm") keys = pmlsm_keys(&p.pmlsm);
      else if (w.size() == 1 && w[0] == "solenoid") keys = solenoid_keys(&p.solenoid);
      else if (w.size() == 1 && w[0] == "limits") keys = limit_keys(&p.limits);
      else if (w.size() == 2 && w[0] == "axis") {
        int a = -1;
        for (int i = 0; i < sp::kAxes; ++i) {
          if (w[1] == kAxisNames[i]) a = i;
        }
        if (a < 0) err(line, "[axis]", "unknown axis '" + w[1] + "' (x, y, theta_z, z, theta_x, theta_y)");
        else {
          p.axis[a].mode = sp::AxisMode::kActive;  // a listed axis is a degree of freedom
          keys = axis_keys(&p.axis[a]);
          section_index = a;
        }
      } else if (w.size() == 2 && (w[0] == "actuator" || w[0] == "sensor")) {
        double n = 0;
        const int max = w[0] == "actuator" ? sp::kMaxActuators : sp::kMaxSensors;
        int& seen = w[0] == "actuator" ? actuators_seen : sensors_seen;
        if (!number(w[1], &n) || n != std::floor(n) || n < 1 || n > max) {
          err(line, "[" + w[0] + "]", "index must be 1.." + std::to_string(max));
        } else if (static_cast<int>(n) != seen + 1) {
          err(line, "[" + w[0] + "]", "numbered in order: expected " + std::to_string(seen + 1));
        } else {
          seen = static_cast<int>(n);
          if (w[0] == "actuator") keys = actuator_keys(&p.actuators[seen - 1]);
          else keys = sensor_keys(&p.sensors[seen - 1]);
          section_index = seen - 1;
        }
      } else {
        err(line, "[" + section + "]",
            "unknown section (stage, body, halbach, pmlsm, solenoid, limits, axis NAME, actuator N, sensor N)");
      }
      continue;
    }
    const auto eq = s.find('=');
    if (eq == std::string::npos) {
      err(line, s, "expected KEY = VALUE");
      continue;
    }
    const std::string k = trim(s.substr(0, eq));
    const std::string v = trim(s.substr(eq + 1));
    if (section.empty()) {
      err(line, k, "outside any section");
      continue;
    }
    if (keys.empty()) continue;  // the section itself was reported
    const auto it = keys.find(k);
    if (it == keys.end()) {
      err(line, k, "unknown key in [" + section + "] (" + key_list(keys) + ")");
      continue;
    }
    if (seen_keys.count(k) != 0) {
      err(line, k, "repeated (first at line " + std::to_string(seen_keys[k]) + ")");
      continue;
    }
    seen_keys[k] = line;
    if (section == "halbach") halbach_set.insert(k);
    if (section.rfind("sensor ", 0) == 0 && (k == "sensitivity_V_per_T" || k == "height_m")) {
      hall_keys.push_back({section_index, line, k});
    }
    if (section.rfind("axis ", 0) == 0 && (k == "kp" || k == "ki" || k == "kd" || k == "imr_omega0_rad_per_s" ||
                                           k == "imr_bandwidth_Hz" || k == "imr_model_bandwidth_Hz" ||
                                           k == "antiwindup_gain" || k == "lqr_weight_h")) {
      loop_keys.push_back({section_index, line, k});
    }
    const std::string why = it->second(v);
    if (!why.empty()) err(line, k, why);
  }
  p.actuator_count = static_cast<std::uint8_t>(actuators_seen);
  p.sensor_count = static_cast<std::uint8_t>(sensors_seen);

  // Whole-profile rules that no single line carries.
  const int end = line;
  if (p.name[0] == '\0') err(end, "name", "missing ([stage] name = ...)");
  if (!family_set) err(end, "family", "missing ([stage] family = halbach_lorentz | iron_core_pmlsm | solenoid_magnet)");
  if (!(p.servo_rate_Hz > 0.0)) err(end, "servo_rate_Hz", "missing ([stage] servo_rate_Hz = ...)");
  if (!(p.body.mass_kg > 0.0)) err(end, "mass_kg", "missing ([body] mass_kg = ...)");
  if (p.startup[0] == sp::StartupStep::kEnd) err(end, "startup", "missing ([stage] startup = ... ready)");
  for (int a = 0; a < sp::kAxes; ++a) {
    const auto& ax = p.axis[a];
    const std::string n = kAxisNames[a];
    const int at = seen_sections.count("axis " + n) ? seen_sections["axis " + n] : end;
    if (ax.mode == sp::AxisMode::kActive && ax.controller.kind == sp::ControllerKind::kNone) {
      err(at, n + ".controller", "an active axis needs a controller");
    }
    if (ax.mode == sp::AxisMode::kPassive && ax.controller.kind != sp::ControllerKind::kNone) {
      err(at, n + ".controller", "a passive axis is left alone: controller must be none");
    }
    if (ax.mode == sp::AxisMode::kActive && !(ax.travel_max > ax.travel_min)) {
      err(at, n + ".travel", "missing (travel = MIN MAX)");
    }
  }
  // The Halbach family's geometry has no defaults: a key left out was 0 (or
  // the cross layout) and the profile passed, then never levitated.
  if (p.family == sp::ActuatorFamily::kHalbachLorentz) {
    std::vector<const char*> required = {"layout", "pitch_m", "magnet_thickness_m", "two_b_star_N_per_A",
                                         "coil_effective_length_m", "coil_side_width_m", "coil_thickness_m",
                                         "coil_turns", "rest_gap_m"};
    if (p.halbach.layout != sp::ForcerLayout::kCustom) required.push_back("lever_arm_m");
    if (p.halbach.layout == sp::ForcerLayout::kTriangle) required.push_back("triangle_alpha_rad");
    const int at = seen_sections.count("halbach") ? seen_sections["halbach"] : end;
    for (const char* k : required) {
      if (halbach_set.count(k) == 0) err(at, k, "missing in [halbach]");
    }
  }
  // A regulator's key on an axis run by the other regulator was taken and
  // never used (a kp on an internal-model axis): said, not ignored.
  for (const KindKey& l : loop_keys) {
    const sp::ControllerKind kind = p.axis[l.index].controller.kind;
    const bool pid_key = l.key == "kp" || l.key == "ki" || l.key == "kd";
    if (pid_key && kind == sp::ControllerKind::kInternalModel) {
      err(l.line, l.key, "belongs to controller = pid2dof; this axis' internal-model regulator is designed by pole "
                         "placement on its plant (docs/STAGES.md)");
    } else if (!pid_key && kind == sp::ControllerKind::kPid2Dof) {
      err(l.line, l.key, "belongs to controller = internal_model; this axis runs pid2dof");
    }
  }
  for (const KindKey& h : hall_keys) {
    if (p.sensors[h.index].kind != sp::SensorKind::kHall) {
      err(h.line, h.key, "only a hall sensor has this key (sensor " + std::to_string(h.index + 1) + " is not one)");
    }
  }
  if (p.limits.peak_current_A > p.limits.hardware_current_A) {
    err(end, "peak_current_A", "above hardware_current_A: the profile must stay inside the hardware");
  }
  if (p.family == sp::ActuatorFamily::kHalbachLorentz && p.halbach.layout != sp::ForcerLayout::kCustom &&
      actuators_seen != 0) {
    err(end, "[actuator]", "the " + std::string(p.halbach.layout == sp::ForcerLayout::kCross ? "cross" : "square/triangle") +
                               " layout places its coils itself: list actuators only with layout = custom");
  }
  return r;
}

ProfileParse load_profile_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) {
    ProfileParse r;
    r.errors.push_back(path + ": cannot read");
    return r;
  }
  std::ostringstream s;
  s << f.rdbuf();
  return parse_profile(s.str(), path);
}

std::vector<std::string> list_profiles(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".profile") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

ProfileParse find_profile(const std::string& name_or_path, const std::string& dir) {
  const bool is_file = name_or_path.find('/') != std::string::npos ||
                       (name_or_path.size() > 8 && name_or_path.compare(name_or_path.size() - 8, 8, ".profile") == 0);
  if (is_file) {
    return load_profile_file(name_or_path);
  }
  // Open the named file directly rather than matching a directory listing:
  // on the SocketCAN VM's 9p mount a readdir can end early under load, and
  // a stage that exists was then reported missing (CI of 459a0f5).
  const std::string direct = dir + "/" + name_or_path + ".profile";
  if (name_or_path.find_first_of("/\\") == std::string::npos && !name_or_path.empty() &&
      std::filesystem::is_regular_file(direct)) {
    return load_profile_file(direct);
  }
  ProfileParse r;
  std::string known;
  for (const auto& n : list_profiles(dir)) known += std::string(known.empty() ? "" : ", ") + n;
  r.errors.push_back("no profile '" + name_or_path + "' in " + dir + " (" + known + ")");
  return r;
}

}  // namespace maglev::profile
