/* Hand-written reference for the benchmark: what a C programmer would write
 * for pt100_sensor's Acquire dataflow (moving average of 8, PT100
 * linearisation by the same table and interpolation, calibration,
 * hysteresis). The benchmark compares the generated code against it. */
#include <stdbool.h>
#include <stdint.h>

#define POINTS 106
static const uint16_t centiohm[POINTS] = {
    1852u, 2283u, 2710u, 3134u, 3554u, 3972u, 4388u, 4800u,
    5211u, 5619u, 6026u, 6430u, 6833u, 7233u, 7633u, 8031u,
    8427u, 8822u, 9216u, 9609u, 10000u, 10390u, 10779u, 11167u,
    11554u, 11940u, 12324u, 12708u, 13090u, 13471u, 13851u, 14229u,
    14607u, 14983u, 15358u, 15733u, 16105u, 16477u, 16848u, 17217u,
    17586u, 17953u, 18319u, 18684u, 19047u, 19410u, 19771u, 20131u,
    20490u, 20848u, 21205u, 21561u, 21915u, 22268u, 22621u, 22972u,
    23321u, 23670u, 24018u, 24364u, 24709u, 25053u, 25396u, 25738u,
    26078u, 26418u, 26756u, 27093u, 27429u, 27764u, 28098u, 28430u,
    28762u, 29092u, 29421u, 29749u, 30075u, 30401u, 30725u, 31049u,
    31371u, 31692u, 32012u, 32330u, 32648u, 32964u, 33279u, 33593u,
    33906u, 34218u, 34528u, 34838u, 35146u, 35453u, 35759u, 36064u,
    36367u, 36670u, 36971u, 37271u, 37570u, 37868u, 38165u, 38460u,
    38755u, 39048u,
};

static uint16_t window[8];
static uint8_t window_index;
static uint8_t window_count;
static int32_t window_sum;
static bool alarm_on;

int16_t hw_temperature;
int16_t hw_sample;
bool hw_alarm;
bool hw_alarm_led;

static int16_t linearize(uint16_t counts)
{
    uint32_t r = ((uint32_t)counts * 40000u) >> 10;
    uint8_t lo = 0u, hi = POINTS - 1u;
    if (r <= centiohm[0]) return -2000;
    if (r >= centiohm[POINTS - 1u]) return 8500;
    while ((uint8_t)(hi - lo) > 1u) {
        uint8_t mid = (uint8_t)((lo + hi) / 2u);
        if (centiohm[mid] <= r) lo = mid; else hi = mid;
    }
    return (int16_t)((-200 + (int16_t)lo * 10) * 10
                     + (int16_t)(((r - centiohm[lo]) * 100u + (uint32_t)(centiohm[hi] - centiohm[lo]) / 2u)
                                 / (uint32_t)(centiohm[hi] - centiohm[lo])));
}

void hw_acquire(uint16_t raw, int16_t cal_gain, int16_t cal_offset, int16_t alarm_high)
{
    uint16_t average;
    int32_t calibrated;
    window_sum -= window[window_index];
    window[window_index] = raw;
    window_sum += raw;
    window_index = (uint8_t)((window_index + 1u) % 8u);
    if (window_count < 8u) window_count++;
    average = (uint16_t)(window_sum / window_count);
    calibrated = (int32_t)linearize(average) * cal_gain / 1000 + cal_offset;
    if (calibrated > 32767) calibrated = 32767;
    if (calibrated < -32768) calibrated = -32768;
    if (calibrated > alarm_high) alarm_on = true;
    else if (calibrated < alarm_high - 20) alarm_on = false;
    hw_temperature = (int16_t)calibrated;
    hw_sample = (int16_t)calibrated;
    hw_alarm = alarm_on;
    hw_alarm_led = alarm_on;
}
