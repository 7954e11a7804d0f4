/* HX711 model shared by the simavr harnesses; see hx711_model.h. */
#include <stdio.h>
#include <math.h>

#include <sim_avr.h>
#include <sim_irq.h>
#include <sim_io.h>
#include <sim_cycle_timers.h>
#include <avr_ioport.h>

#include "hx711_model.h"

#define F_CPU_HZ 16000000.0

static avr_t *avr;
static hx_value_fn hx_value;
static int hx_sps;                  /* 0: no HX711 connected */
static uint64_t hx_k;               /* conversions made */
static int hx_ready;                /* a conversion waits or is being read */
static int hx_bit;                  /* SCK rising edges of the read in progress */
static int32_t hx_val;
static int hx_down, hx_unplugged, hx_sck;
static avr_cycle_count_t hx_rise, hx_max_high;
static uint64_t hx_pulses, hx_stray;
static avr_irq_t *dout_irq;

/* DOUT is set as the port's external level, not only raised: simavr 1.6 re-applies the internal
 * pull-up (PORTD2 = 1) to the input pin on every write to PORTD (each SCK edge), which would
 * override a level that was merely raised. */
static void dout(uint32_t level) {
  avr_ioport_external_t e = {.name = 'D', .mask = 1u << 2, .value = (level ? 1u : 0u) << 2};
  avr_ioctl(avr, AVR_IOCTL_IOPORT_SET_EXTERNAL('D'), &e);
  avr_raise_irq(dout_irq, level ? 1 : 0);
}

static avr_cycle_count_t hx_period(void) { return (avr_cycle_count_t)llround(F_CPU_HZ / hx_sps); }

static avr_cycle_count_t hx_conv_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)param;
  if (hx_down || hx_unplugged) return 0;
  int32_t v = hx_value(hx_k++, a->cycle);
  if (hx_ready && hx_bit > 0) {
    fprintf(stderr, "#HX_LOST %llu %d\n", (unsigned long long)a->cycle, v); /* read in progress keeps its data */
  } else {
    if (hx_ready) fprintf(stderr, "#HX_LOST %llu %d\n", (unsigned long long)a->cycle, hx_val);
    hx_val = v;
    hx_ready = 1;
    hx_bit = 0;
    dout(0);
  }
  return when + hx_period();
}

static avr_cycle_count_t hx_unplug_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)when; (void)param;
  hx_unplugged = 1;
  hx_ready = 0;
  avr_cycle_timer_cancel(a, hx_conv_cb, NULL);
  dout(1);
  return 0;
}

static avr_cycle_count_t hx_powerdown_cb(struct avr_t *a, avr_cycle_count_t when, void *param) {
  (void)when; (void)param;
  if (!hx_sck || hx_down || hx_unplugged) return 0;
  hx_down = 1;
  hx_ready = 0;
  hx_bit = 0;
  fprintf(stderr, "#HX_POWERDOWN %llu\n", (unsigned long long)a->cycle);
  avr_cycle_timer_cancel(a, hx_conv_cb, NULL);
  dout(1);
  return 0;
}

static void sck_cb(struct avr_irq_t *irq, uint32_t value, void *param) {
  (void)irq; (void)param;
  int v = value ? 1 : 0;
  if (v == hx_sck) return;
  hx_sck = v;
  if (v) {
    hx_rise = avr->cycle;
    if (hx_unplugged || !hx_sps) {
      hx_stray++;
      return;
    }
    if (!hx_down) avr_cycle_timer_register(avr, 960, hx_powerdown_cb, NULL); /* 60 us */
    if (hx_down) return;
    if (!hx_ready) {
      hx_stray++;
      return;
    }
    hx_bit++;
    dout(hx_bit <= 24 ? (uint32_t)((hx_val >> (24 - hx_bit)) & 1) : 1u);
    return;
  }
  avr_cycle_count_t d = avr->cycle - hx_rise;
  if (d > hx_max_high) hx_max_high = d;
  hx_pulses++;
  if (hx_unplugged) return;
  avr_cycle_timer_cancel(avr, hx_powerdown_cb, NULL);
  if (hx_down) {
    hx_down = 0;
    fprintf(stderr, "#HX_POWERUP %llu\n", (unsigned long long)avr->cycle);
    avr_cycle_timer_register(avr, (avr_cycle_count_t)llround(F_CPU_HZ * (hx_sps == 10 ? 0.4 : 0.05)),
                             hx_conv_cb, NULL);
    return;
  }
  if (hx_ready && hx_bit == 25) {
    fprintf(stderr, "#HX %llu %d\n", (unsigned long long)avr->cycle, hx_val);
    hx_ready = 0;
    hx_bit = 0;
  }
}

void hx_attach(avr_t *a, int sps, double first_s, double stop_s, hx_value_fn value) {
  avr = a;
  hx_sps = sps;
  hx_value = value;
  /* DOUT (PD2) high = not ready, or no HX711 (the pull-up); SCK (PD3) watched */
  dout_irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 2);
  dout(1);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 3), sck_cb, NULL);
  if (hx_sps) {
    double first = first_s >= 0 ? first_s : 1.0 / hx_sps;
    avr_cycle_timer_register(avr, (avr_cycle_count_t)llround(first * F_CPU_HZ) + 1, hx_conv_cb, NULL);
    if (stop_s >= 0)
      avr_cycle_timer_register(avr, (avr_cycle_count_t)llround(stop_s * F_CPU_HZ) + 1, hx_unplug_cb, NULL);
  }
}

void hx_report(void) {
  if (hx_sck && avr->cycle - hx_rise > hx_max_high) hx_max_high = avr->cycle - hx_rise;
  fprintf(stderr, "#HX_SCK %llu %llu %llu\n", (unsigned long long)hx_max_high,
          (unsigned long long)hx_pulses, (unsigned long long)hx_stray);
}
