/*
 * The simulated MCU shared by the simavr harnesses (fsrlab_sim.c, fsrlab_twin.c): an ATmega328P at
 * 16 MHz, 5 V supply and reference, the firmware loaded from its ELF, simavr's own log off; its USART0.
 */
#ifndef FSRLAB_MCU_H
#define FSRLAB_MCU_H

#include <sim_avr.h>
#include <sim_irq.h>

/* The MCU running `elf` (an ELF file, or an Intel hex file when the name ends in .hex), or NULL after
 * one line on stderr saying why. */
avr_t *mcu_load(const char *elf);

/* USART0 without simavr's stdio echo and poll sleep; every byte the firmware sends goes to `out_cb`.
 * Returns the IRQ that feeds bytes into the firmware's receiver. Also works around simavr 1.6's
 * UDRE0 (see mcu.c). */
avr_irq_t *mcu_uart(avr_t *avr, avr_irq_notify_t out_cb);

#endif
