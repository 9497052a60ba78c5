// Time-of-day lighting: sun path, atmospheric reddening, sky colours and lamps. A simple analytic model (not a
// physical sky): it only has to give plausible, smoothly varying day / sunset / night light for the dataset.
#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>

#include "ngi/render.hpp"

namespace ngi {
namespace {

float smoothstep(float a, float b, float x) {
    const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

}  // namespace

Lighting lighting_at(float hours, float sun_azimuth) {
    const float pi = glm::pi<float>();
    const float h = std::fmod(std::fmod(hours, 24.0f) + 24.0f, 24.0f);
    // Day angle: 0 at 6 h (sunrise), pi/2 at noon, pi at 18 h (sunset); the sun culminates 70 degrees high.
    const float day_angle = (h - 6.0f) / 12.0f * pi;
    const float sin_e = std::sin(day_angle) * std::sin(glm::radians(70.0f));
    const float cos_e = std::sqrt(std::max(0.0f, 1.0f - sin_e * sin_e));
    const float az = sun_azimuth + (day_angle - 0.5f * pi);  // east -> south(ish) -> west over the day

    Lighting l;
    l.sun.direction = glm::normalize(glm::vec3(cos_e * std::sin(az), sin_e, cos_e * std::cos(az)));
    l.sun.angular_radius = 0.01f;  // about twice the real sun: slightly soft shadow edges
    // Extinction through an air mass ~ 1/sin(elevation): blue is scattered out first, so the low sun turns
    // orange, then red, then sets (the last factor fades it across the horizon).
    const glm::vec3 tau(0.05f, 0.10f, 0.22f);
    const float air_mass = 1.0f / std::max(sin_e, 0.03f);
    const glm::vec3 transmittance = glm::exp(-tau * air_mass);
    const float above = smoothstep(-0.02f, 0.02f, sin_e);
    l.sun.irradiance = 3.6f * transmittance * above;

    const float day = smoothstep(-0.1f, 0.25f, sin_e);            // sky brightness, lingering after sunset
    const float twilight = std::exp(-std::pow((sin_e - 0.02f) / 0.08f, 2.0f));  // orange horizon near sunset
    const glm::vec3 zenith_day(0.10f, 0.20f, 0.45f), horizon_day(0.35f, 0.45f, 0.60f);
    const glm::vec3 zenith_night(0.004f, 0.006f, 0.015f), horizon_night(0.006f, 0.008f, 0.015f);
    l.sky.zenith = glm::mix(zenith_night, zenith_day, day) + twilight * glm::vec3(0.03f, 0.02f, 0.05f);
    l.sky.horizon = glm::mix(horizon_night, horizon_day, day) + twilight * glm::vec3(0.30f, 0.13f, 0.04f);
    const float tmax = std::max({transmittance.r, transmittance.g, transmittance.b});
    l.sky.glow = 0.25f * smoothstep(-0.1f, 0.1f, sin_e) * transmittance / tmax;
    // The world beyond the grid: ground of albedo 0.25 lit by the sun and (roughly) the sky.
    const float ground_albedo = 0.25f;
    l.sky.ground = ground_albedo * (l.sun.irradiance * std::max(sin_e, 0.0f) / pi +
                                    0.5f * (l.sky.zenith + l.sky.horizon));
    l.lamp_level = 1.0f - smoothstep(-0.05f, 0.12f, sin_e);
    return l;
}

glm::vec3 sky_radiance(const Sky& sky, const Sun& sun, glm::vec3 d) {
    if (d.y < 0.0f) return sky.ground;
    float g = 0.5f * (1.0f + glm::dot(d, sun.direction));
    g *= g; g *= g; g *= g;
    return sky.horizon + (sky.zenith - sky.horizon) * std::sqrt(d.y) + sky.glow * g;
}

}  // namespace ngi
