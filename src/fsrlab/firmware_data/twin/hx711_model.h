/*
 * HX711 model shared by the simavr harnesses (fsrlab_sim.c, fsrlab_twin.c): DOUT on D2 (PD2), SCK on
 * D3 (PD3) of an ATmega328P.
 *
 * Model (datasheet, Avia Semiconductor HX711 rev. 2.0): a conversion is ready every 1/SPS; DOUT then
 * goes low. Each SCK rising edge shifts out the next bit, MSB first (DOUT changes at the rising edge
 * and holds until the next one); the 25th rising edge (gain 128, channel A) sets DOUT high until the
 * next conversion. A conversion not read before the next one is replaced. SCK high for more than
 * 60 us powers the chip down (no conversions); SCK low again powers it up, and the next conversion is
 * ready after the settling time, 400 ms at 10 SPS and 50 ms at 80 SPS.
 *
 * Diagnostics on stderr, one per line: #HX <cycle> <value>, #HX_POWERDOWN <cycle>,
 * #HX_POWERUP <cycle>, #HX_LOST <cycle> <value> (see fsrlab_sim.c), and hx_report() at the end:
 * #HX_SCK <max_high> <pulses> <stray>.
 */
#ifndef FSRLAB_HX711_MODEL_H
#define FSRLAB_HX711_MODEL_H

#include <stdint.h>
#include <sim_avr.h>

/* Raw value (24-bit two's complement) of conversion number k, made at CPU cycle `cycle`. */
typedef int32_t (*hx_value_fn)(uint64_t k, avr_cycle_count_t cycle);

/* Connect the model to `avr`. sps: 10 or 80, or 0 for no HX711 (DOUT held high, as the firmware's
 * pull-up does on a real board). first_s: time of the first conversion [s] (< 0: 1/SPS).
 * stop_s: from then on the HX711 is unplugged (< 0: never). */
void hx_attach(avr_t *avr, int sps, double first_s, double stop_s, hx_value_fn value);

/* End-of-run line #HX_SCK <max_high> <pulses> <stray>. */
void hx_report(void);

#endif
