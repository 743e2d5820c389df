// STM32H743 register definitions, written for this project from the reference
// manual RM0433 (rev 7/8) and the Cortex-M7 generic user guide. CMSIS and the
// ST headers are deliberately not used: only what our drivers touch is here,
// each block names its RM0433 section so a reviewer can check every offset
// and bit against the manual.
//
// Style: constexpr peripheral base addresses, register OFFSETS, and bit/field
// constants. Drivers add offset to an instance base and go through a
// register-access policy (maglev/stm32h7/register_bus.hpp), so the very same
// driver code runs against MMIO on the target and against a fake in host tests.
#pragma once

#include <cstdint>

namespace maglev::stm32h7 {

using Addr = std::uintptr_t;

constexpr std::uint32_t bit(unsigned n) { return 1u << n; }
// A multi-bit field value placed at `shift`.
constexpr std::uint32_t field(std::uint32_t value, unsigned shift) { return value << shift; }

// --- Memory map, RM0433 §2.3.2 table 7/8 ---------------------------------------------
namespace memory {
inline constexpr Addr kItcm = 0x00000000;        // 64 KB
inline constexpr Addr kFlashBank1 = 0x08000000;  // 1 MB, 8 x 128 KB sectors
inline constexpr Addr kFlashBank2 = 0x08100000;  // 1 MB, 8 x 128 KB sectors
inline constexpr std::uint32_t kFlashSectorBytes = 128 * 1024;
inline constexpr std::uint32_t kFlashWordBytes = 32;  // 256-bit flash word
inline constexpr Addr kDtcm = 0x20000000;             // 128 KB
inline constexpr Addr kAxiSram = 0x24000000;          // 512 KB (D1)
inline constexpr Addr kSram1 = 0x30000000;            // 128 KB (D2)
inline constexpr Addr kSram2 = 0x30020000;            // 128 KB (D2)
inline constexpr Addr kSram3 = 0x30040000;            // 32 KB (D2)
inline constexpr Addr kSram4 = 0x38000000;            // 64 KB (D3)
inline constexpr Addr kBackupSram = 0x38800000;       // 4 KB (battery-backed domain)
}  // namespace memory

// --- RCC, RM0433 §8.7 (base 0x5802 4400) ----------------------------------------------
namespace rcc {
inline constexpr Addr kBase = 0x58024400;
inline constexpr Addr kCr = 0x000;
inline constexpr std::uint32_t kCrHsion = bit(0);
inline constexpr std::uint32_t kCrHsirdy = bit(2);
inline constexpr std::uint32_t kCrHseon = bit(16);
inline constexpr std::uint32_t kCrHserdy = bit(17);
inline constexpr std::uint32_t kCrHsebyp = bit(18);  // external clock (ST-LINK MCO), no crystal
inline constexpr std::uint32_t kCrPll1on = bit(24);
inline constexpr std::uint32_t kCrPll1rdy = bit(25);
inline constexpr Addr kCfgr = 0x010;
inline constexpr unsigned kCfgrSwShift = 0;   // SW[2:0]
inline constexpr unsigned kCfgrSwsShift = 3;  // SWS[5:3]
inline constexpr std::uint32_t kCfgrSwMask = 0x7;
inline constexpr std::uint32_t kSwPll1 = 3;
inline constexpr Addr kD1cfgr = 0x018;  // HPRE[3:0], D1PPRE[6:4], D1CPRE[11:8]
inline constexpr Addr kD2cfgr = 0x01C;  // D2PPRE1[6:4], D2PPRE2[10:8]
inline constexpr Addr kD3cfgr = 0x020;  // D3PPRE[6:4]
inline constexpr std::uint32_t kHpreDiv2 = 0x8;    // 4-bit AHB prescaler code: /2
inline constexpr std::uint32_t kPpreDiv2 = 0x4;    // 3-bit APB prescaler code: /2
inline constexpr Addr kPllckselr = 0x028;  // PLLSRC[1:0], DIVM1[9:4]
inline constexpr std::uint32_t kPllsrcHse = 2;
inline constexpr unsigned kDivm1Shift = 4;
inline constexpr Addr kPllcfgr = 0x02C;
inline constexpr unsigned kPll1rgeShift = 2;        // PLL1RGE[3:2]: 3 = 8..16 MHz ref
inline constexpr std::uint32_t kPll1vcosel = bit(1);  // 1 = medium VCO; 0 = wide (192..960 MHz)
inline constexpr std::uint32_t kDivp1en = bit(16);
inline constexpr std::uint32_t kDivq1en = bit(17);
inline constexpr std::uint32_t kDivr1en = bit(18);
inline constexpr Addr kPll1divr = 0x030;  // DIVN1[8:0], DIVP1[15:9], DIVQ1[22:16], DIVR1[30:24]; all "value - 1"
inline constexpr Addr kPll1fracr = 0x034;
inline constexpr Addr kD2ccip1r = 0x050;  // SPI123SEL[14:12] (0 = pll1_q), FDCANSEL[29:28] (1 = pll1_q)
inline constexpr unsigned kSpi123selShift = 12;
inline constexpr unsigned kFdcanselShift = 28;
inline constexpr Addr kD2ccip2r = 0x054;  // USART234578SEL[2:0], USART16SEL[5:3] (0 = pclk)
inline constexpr Addr kCsr = 0x074;       // LSION bit 0, LSIRDY bit 1
inline constexpr Addr kAhb1enr = 0x0D8;   // DMA1EN 0, DMA2EN 1
inline constexpr Addr kAhb2enr = 0x0DC;   // SRAM1EN 29, SRAM2EN 30, SRAM3EN 31
inline constexpr Addr kAhb4enr = 0x0E0;   // GPIOxEN 0..10, BKPRAMEN 28
inline constexpr Addr kApb1lenr = 0x0E8;  // TIM2EN 0, TIM3EN 1, TIM4EN 2, TIM5EN 3, USART3EN 18
inline constexpr Addr kApb1henr = 0x0EC;  // FDCANEN 8
inline constexpr Addr kApb2enr = 0x0F0;   // TIM1EN 0, TIM8EN 1, SPI1EN 12, SPI4EN 13
inline constexpr Addr kApb4enr = 0x0F4;   // SYSCFGEN 1
}  // namespace rcc

// --- PWR, RM0433 §6.8 (base 0x5802 4800) ----------------------------------------------
namespace pwr {
inline constexpr Addr kBase = 0x58024800;
inline constexpr Addr kCr1 = 0x00;     // DBP bit 8: backup-domain write access
inline constexpr std::uint32_t kCr1Dbp = bit(8);
inline constexpr Addr kCsr1 = 0x04;    // ACTVOSRDY bit 13
inline constexpr std::uint32_t kCsr1Actvosrdy = bit(13);
inline constexpr Addr kCr2 = 0x08;     // BREN bit 0 (backup regulator), BRRDY bit 16
inline constexpr std::uint32_t kCr2Bren = bit(0);
inline constexpr std::uint32_t kCr2Brrdy = bit(16);
inline constexpr Addr kCr3 = 0x0C;     // BYPASS 0, LDOEN 1, SCUEN 2
inline constexpr std::uint32_t kCr3Bypass = bit(0);
inline constexpr std::uint32_t kCr3Ldoen = bit(1);
inline constexpr std::uint32_t kCr3Scuen = bit(2);
inline constexpr Addr kD3cr = 0x18;    // VOS[15:14] (3 = scale 1), VOSRDY bit 13
inline constexpr unsigned kD3crVosShift = 14;
inline constexpr std::uint32_t kD3crVosrdy = bit(13);
}  // namespace pwr

// --- SYSCFG, RM0433 §12.3 (base 0x5800 0400) --------------------------------------------
namespace syscfg {
inline constexpr Addr kBase = 0x58000400;
inline constexpr Addr kPwrcr = 0x2C;   // ODEN bit 0: VOS0 (overdrive) on top of scale 1
inline constexpr std::uint32_t kPwrcrOden = bit(0);
}  // namespace syscfg

// --- Embedded flash interface, RM0433 §4.9 (base 0x5200 2000) -------------------------
namespace flash {
inline constexpr Addr kBase = 0x52002000;
inline constexpr Addr kAcr = 0x000;  // LATENCY[3:0], WRHIGHFREQ[5:4]
inline constexpr unsigned kAcrWrhighfreqShift = 4;
// Per-bank registers: bank 2's are bank 1's + 0x100.
inline constexpr Addr kBank2Offset = 0x100;
inline constexpr Addr kKeyr = 0x004;
inline constexpr Addr kCr = 0x00C;
inline constexpr Addr kSr = 0x010;
inline constexpr Addr kCcr = 0x014;
inline constexpr std::uint32_t kKey1 = 0x45670123;
inline constexpr std::uint32_t kKey2 = 0xCDEF89AB;
// FLASH_CRx
inline constexpr std::uint32_t kCrLock = bit(0);
inline constexpr std::uint32_t kCrPg = bit(1);
inline constexpr std::uint32_t kCrSer = bit(2);
inline constexpr std::uint32_t kCrBer = bit(3);
inline constexpr unsigned kCrPsizeShift = 4;  // PSIZE[5:4]: 0 x8, 1 x16, 2 x32, 3 x64
inline constexpr std::uint32_t kCrPsizeMask = 0x3u << 4;
inline constexpr std::uint32_t kCrFw = bit(6);
inline constexpr std::uint32_t kCrStart = bit(7);
inline constexpr unsigned kCrSnbShift = 8;  // SNB[10:8]
inline constexpr std::uint32_t kCrSnbMask = 0x7u << 8;
// FLASH_SRx (the same error bit positions are the clear bits in FLASH_CCRx)
inline constexpr std::uint32_t kSrBsy = bit(0);
inline constexpr std::uint32_t kSrWbne = bit(1);
inline constexpr std::uint32_t kSrQw = bit(2);
inline constexpr std::uint32_t kSrEop = bit(16);
inline constexpr std::uint32_t kSrWrperr = bit(17);
inline constexpr std::uint32_t kSrPgserr = bit(18);
inline constexpr std::uint32_t kSrStrberr = bit(19);
inline constexpr std::uint32_t kSrIncerr = bit(21);
inline constexpr std::uint32_t kSrOperr = bit(22);
inline constexpr std::uint32_t kSrRdperr = bit(23);
inline constexpr std::uint32_t kSrRdserr = bit(24);
inline constexpr std::uint32_t kSrSneccerr = bit(25);
inline constexpr std::uint32_t kSrDbeccerr = bit(26);
inline constexpr std::uint32_t kSrProgramErrors =
    kSrWrperr | kSrPgserr | kSrStrberr | kSrIncerr | kSrOperr;
inline constexpr std::uint32_t kSrAllErrors =
    kSrProgramErrors | kSrRdperr | kSrRdserr | kSrSneccerr | kSrDbeccerr;
}  // namespace flash

// --- GPIO, RM0433 §11.4 (ports A..K at 0x5802 0000 + 0x400 * n) --------------------
namespace gpio {
inline constexpr Addr kPortA = 0x58020000;
constexpr Addr port(char letter) { return kPortA + 0x400u * static_cast<Addr>(letter - 'A'); }
inline constexpr Addr kModer = 0x00;    // 2 bits/pin: 0 in, 1 out, 2 AF, 3 analog
inline constexpr Addr kOtyper = 0x04;
inline constexpr Addr kOspeedr = 0x08;  // 2 bits/pin
inline constexpr Addr kPupdr = 0x0C;    // 2 bits/pin: 1 pull-up, 2 pull-down
inline constexpr Addr kIdr = 0x10;
inline constexpr Addr kOdr = 0x14;
inline constexpr Addr kBsrr = 0x18;     // BSx bits 0..15 set, BRx bits 16..31 reset
inline constexpr Addr kAfrl = 0x20;
inline constexpr Addr kAfrh = 0x24;
inline constexpr std::uint32_t kModeInput = 0, kModeOutput = 1, kModeAlternate = 2;
// BSRR value that drives pin `n` high (BSn) or low (BRn): no read-modify-write.
constexpr std::uint32_t bsrr(unsigned n, bool high) { return high ? (1u << n) : (1u << (n + 16u)); }
}  // namespace gpio

// --- EXTI, RM0433 §20.6 (CPU1 registers, base 0x5800 0000) -------------------------------
namespace exti {
inline constexpr Addr kBase = 0x58000000;
inline constexpr Addr kRtsr1 = 0x00;
inline constexpr Addr kFtsr1 = 0x04;
inline constexpr Addr kCpuimr1 = 0x80;
inline constexpr Addr kCpupr1 = 0x88;  // write 1 to clear
}  // namespace exti
namespace syscfg {
inline constexpr Addr kExticr1 = 0x08;  // EXTICR1..4 at 0x08..0x14, 4 bits per line
}

// --- General-purpose / advanced timers, RM0433 §38/§39 ------------------------------
namespace tim {
inline constexpr Addr kTim1 = 0x40010000;
inline constexpr Addr kTim2 = 0x40000000;  // 32-bit counter
inline constexpr Addr kTim3 = 0x40000400;
inline constexpr Addr kTim4 = 0x40000800;
inline constexpr Addr kTim5 = 0x40000C00;  // 32-bit counter
inline constexpr Addr kTim8 = 0x40010400;
inline constexpr Addr kCr1 = 0x00;
inline constexpr std::uint32_t kCr1Cen = bit(0);
inline constexpr std::uint32_t kCr1Urs = bit(2);
inline constexpr std::uint32_t kCr1Dir = bit(4);
inline constexpr std::uint32_t kCr1Arpe = bit(7);
inline constexpr Addr kCr2 = 0x04;           // MMS[6:4]
inline constexpr Addr kSmcr = 0x08;          // SMS[2:0] (+ SMS[3] at bit 16)
inline constexpr std::uint32_t kSmsEncoderMode3 = 3;  // count on TI1 and TI2 edges (x4)
inline constexpr Addr kDier = 0x0C;          // UIE 0, CC1IE..CC4IE 1..4
inline constexpr Addr kSr = 0x10;            // UIF 0, CC1IF..CC4IF 1..4 (write 0 to clear)
inline constexpr Addr kEgr = 0x14;           // UG bit 0
inline constexpr Addr kCcmr1 = 0x18;         // CC1S[1:0], IC1F[7:4], CC2S[9:8], IC2F[15:12]; OC1M[6:4]
inline constexpr Addr kCcmr2 = 0x1C;         // same layout for channels 3 and 4
inline constexpr Addr kCcer = 0x20;          // CCxE at 4(x-1), CCxP at 4(x-1)+1
inline constexpr Addr kCnt = 0x24;
inline constexpr Addr kPsc = 0x28;
inline constexpr Addr kArr = 0x2C;
inline constexpr Addr kCcr1 = 0x34;
inline constexpr Addr kCcr2 = 0x38;
inline constexpr Addr kCcr3 = 0x3C;
inline constexpr Addr kCcr4 = 0x40;
inline constexpr Addr kBdtr = 0x44;          // MOE bit 15 (advanced timers only)
inline constexpr std::uint32_t kBdtrMoe = bit(15);
inline constexpr std::uint32_t kOcModePwm2 = 7;  // OCxM = 0111: inactive while CNT < CCR
}  // namespace tim

// --- SPI (SPI v2 of the H7), RM0433 §50.11 ------------------------------------------------
namespace spi {
inline constexpr Addr kSpi1 = 0x40013000;
inline constexpr Addr kSpi2 = 0x40003800;
inline constexpr Addr kSpi3 = 0x40003C00;
inline constexpr Addr kSpi4 = 0x40013400;
inline constexpr Addr kCr1 = 0x00;
inline constexpr std::uint32_t kCr1Spe = bit(0);
inline constexpr std::uint32_t kCr1Cstart = bit(9);
inline constexpr std::uint32_t kCr1Ssi = bit(12);
inline constexpr Addr kCr2 = 0x04;     // TSIZE[15:0]
inline constexpr Addr kCfg1 = 0x08;    // DSIZE[4:0] = bits - 1, FTHLV[8:5], MBR[30:28]
inline constexpr unsigned kCfg1MbrShift = 28;
inline constexpr std::uint32_t kCfg1Rxdmaen = bit(14);  // §50.11.3: RX-packet DMA request (TXDMAEN is bit 15)
inline constexpr Addr kCfg2 = 0x0C;
// COMM[18:17] (§50.11.4): 0 full duplex, 1 simplex transmitter, 2 simplex
// receiver (the master clocks TSIZE frames after CSTART with no TXDR writes).
inline constexpr unsigned kCfg2CommShift = 17;
inline constexpr std::uint32_t kCfg2CommMask = 0x3u << 17;
inline constexpr std::uint32_t kCommSimplexReceiver = 2;
inline constexpr std::uint32_t kCfg2Master = bit(22);
inline constexpr std::uint32_t kCfg2Cpha = bit(24);
inline constexpr std::uint32_t kCfg2Cpol = bit(25);
inline constexpr std::uint32_t kCfg2Ssm = bit(26);
inline constexpr std::uint32_t kCfg2Afcntr = bit(31);  // keep driving pins while SPE = 0
inline constexpr Addr kIer = 0x10;     // §50.11.5
inline constexpr std::uint32_t kIerEotie = bit(3);  // EOT (and SUSP, TXC) interrupt enable
inline constexpr Addr kSr = 0x14;
inline constexpr std::uint32_t kSrRxp = bit(0);
inline constexpr std::uint32_t kSrTxp = bit(1);
inline constexpr std::uint32_t kSrEot = bit(3);
inline constexpr std::uint32_t kSrOvr = bit(6);  // RX overrun (a frame arrived with RxFIFO full)
inline constexpr Addr kIfcr = 0x18;    // EOTC 3, TXTFC 4, OVRC 6
inline constexpr std::uint32_t kIfcrEotc = bit(3);
inline constexpr std::uint32_t kIfcrTxtfc = bit(4);
inline constexpr std::uint32_t kIfcrOvrc = bit(6);
inline constexpr Addr kTxdr = 0x20;
inline constexpr Addr kRxdr = 0x30;
// CFG1 for SCLK = kernel / 2^(mbr+1) (MBR code 0..7) and `word_bits`-bit frames.
constexpr std::uint32_t cfg1(unsigned mbr, unsigned word_bits) {
  return ((mbr & 7u) << kCfg1MbrShift) | (word_bits - 1u);
}
// CFG2 of a master with software slave management (NSS internal) that keeps
// driving its pins while SPE = 0, in SPI mode (cpol, cpha), full duplex.
constexpr std::uint32_t cfg2_master(bool cpol, bool cpha) {
  return kCfg2Master | kCfg2Ssm | kCfg2Afcntr | (cpol ? kCfg2Cpol : 0u) | (cpha ? kCfg2Cpha : 0u);
}
}  // namespace spi

// --- DMA / DMAMUX, RM0433 §15 (DMA1/DMA2) and §17 (DMAMUX1) ----------------------------
namespace dma {
inline constexpr Addr kDma1 = 0x40020000;
inline constexpr Addr kDma2 = 0x40020400;
// §15.5.5..15.5.10: interrupt status LISR (streams 0..3) / HISR (4..7) and
// their write-1-to-clear twins LIFCR / HIFCR; stream n's registers at
// 0x10 + 0x18 n: SxCR, SxNDTR, SxPAR, SxM0AR, SxM1AR, SxFCR.
inline constexpr Addr kLisr = 0x00, kHisr = 0x04, kLifcr = 0x08, kHifcr = 0x0C;
constexpr Addr stream(Addr dma, unsigned n) { return dma + 0x10 + 0x18 * n; }  // SxCR at +0
inline constexpr Addr kSxCr = 0x00, kSxNdtr = 0x04, kSxPar = 0x08, kSxM0ar = 0x0C, kSxFcr = 0x14;
// Status/clear flags of one stream, before the shift below: FEIF 0, DMEIF 2,
// TEIF 3, HTIF 4, TCIF 5.
inline constexpr std::uint32_t kFlagFe = bit(0);
inline constexpr std::uint32_t kFlagDme = bit(2);
inline constexpr std::uint32_t kFlagTe = bit(3);
inline constexpr std::uint32_t kFlagHt = bit(4);
inline constexpr std::uint32_t kFlagTc = bit(5);
inline constexpr std::uint32_t kFlagsAll = kFlagFe | kFlagDme | kFlagTe | kFlagHt | kFlagTc;
// Stream n's flags sit at 0, 6, 16, 22 in LISR (n = 0..3) and HISR (n = 4..7).
constexpr unsigned flag_shift(unsigned n) { return (n % 4u) * 6u + ((n % 4u) >= 2u ? 4u : 0u); }
constexpr Addr isr(unsigned n) { return n < 4u ? kLisr : kHisr; }
constexpr Addr ifcr(unsigned n) { return n < 4u ? kLifcr : kHifcr; }
// SxCR (§15.5.11)
inline constexpr std::uint32_t kCrEn = bit(0);
inline constexpr std::uint32_t kCrDmeie = bit(1);
inline constexpr std::uint32_t kCrTeie = bit(2);
inline constexpr std::uint32_t kCrTcie = bit(4);
inline constexpr unsigned kCrDirShift = 6;   // DIR[7:6]: 0 peripheral->memory, 1 memory->peripheral
inline constexpr std::uint32_t kDirPeripheralToMemory = 0;
inline constexpr std::uint32_t kCrMinc = bit(10);
inline constexpr unsigned kCrPsizeShift = 11;  // PSIZE[12:11] / MSIZE[14:13]: 0 byte, 1 half-word, 2 word
inline constexpr unsigned kCrMsizeShift = 13;
inline constexpr std::uint32_t kSizeWord = 2;
inline constexpr unsigned kCrPlShift = 16;     // PL[17:16]: 3 = very high
// SxFCR (§15.5.16): 0 = DMDIS clear -> direct mode (no FIFO; PSIZE = MSIZE).
// DMAMUX1 (§17.6.1): channel c's CxCR at +4 c, DMAREQ_ID[6:0]; channels 0..7
// serve DMA1 streams 0..7, channels 8..15 DMA2 streams 0..7 (§17.3.2).
inline constexpr Addr kDmamux1 = 0x40020800;
constexpr Addr dmamux_channel(Addr dma, unsigned n) { return kDmamux1 + 4u * ((dma == kDma2 ? 8u : 0u) + n); }
// DMAMUX1 request inputs (§17.3.2 table 121).
inline constexpr std::uint32_t kReqSpi2Rx = 39;
inline constexpr std::uint32_t kReqSpi3Rx = 61;
}  // namespace dma

// --- FDCAN, RM0433 §56.5 ------------------------------------------------------------------
namespace fdcan {
inline constexpr Addr kFdcan1 = 0x4000A000;
inline constexpr Addr kFdcan2 = 0x4000A400;
inline constexpr Addr kMessageRam = 0x4000AC00;  // 10 KB shared by both instances
inline constexpr std::uint32_t kMessageRamBytes = 10 * 1024;
inline constexpr Addr kDbtp = 0x00C;   // TDC 23, DBRP[20:16], DTSEG1[12:8], DTSEG2[7:4], DSJW[3:0]
inline constexpr Addr kCccr = 0x018;
inline constexpr std::uint32_t kCccrInit = bit(0);
inline constexpr std::uint32_t kCccrCce = bit(1);
inline constexpr std::uint32_t kCccrFdoe = bit(8);
inline constexpr std::uint32_t kCccrBrse = bit(9);
inline constexpr std::uint32_t kCccrTxp = bit(14);
inline constexpr Addr kNbtp = 0x01C;   // NSJW[31:25], NBRP[24:16], NTSEG1[15:8], NTSEG2[6:0]
inline constexpr Addr kEcr = 0x040;
inline constexpr Addr kPsr = 0x044;    // BO bit 7
inline constexpr std::uint32_t kPsrBo = bit(7);
inline constexpr Addr kTdcr = 0x048;   // TDCO[14:8], TDCF[6:0]
inline constexpr Addr kIr = 0x050;     // RF0N 0, RF0L 3 (message lost), BO 25
inline constexpr std::uint32_t kIrRf0l = bit(3);
inline constexpr std::uint32_t kIrBo = bit(25);
inline constexpr Addr kIe = 0x054;
inline constexpr Addr kIls = 0x058;
inline constexpr Addr kIle = 0x05C;
inline constexpr Addr kGfc = 0x080;    // ANFS[5:4], ANFE[3:2], RRFS 1, RRFE 0
inline constexpr Addr kSidfc = 0x084;  // LSS[23:16], FLSSA[15:2]
inline constexpr Addr kXidfc = 0x088;  // LSE[22:16], FLESA[15:2]
inline constexpr Addr kRxf0c = 0x0A0;  // F0OM 31, F0WM[30:24], F0S[22:16], F0SA[15:2]
inline constexpr Addr kRxf0s = 0x0A4;  // RF0L 25, F0F 24, F0PI[21:16], F0GI[13:8], F0FL[6:0]
inline constexpr Addr kRxf0a = 0x0A8;  // F0AI[5:0]
inline constexpr Addr kRxbc = 0x0AC;
inline constexpr Addr kRxf1c = 0x0B0;
inline constexpr Addr kRxesc = 0x0BC;  // F0DS[2:0], F1DS[6:4], RBDS[10:8]; 7 = 64 bytes
inline constexpr Addr kTxbc = 0x0C0;   // TFQM 30, TFQS[29:24], NDTB[21:16], TBSA[15:2]
inline constexpr Addr kTxfqs = 0x0C4;  // TFQF 21, TFQPI[20:16], TFGI[12:8], TFFL[5:0]
inline constexpr std::uint32_t kTxfqsTfqf = bit(21);
inline constexpr Addr kTxesc = 0x0C8;  // TBDS[2:0]
inline constexpr Addr kTxbar = 0x0D0;
inline constexpr Addr kTxefc = 0x0F0;
// Tx/Rx buffer element header words (RM0433 §56.4.18/§56.4.19).
inline constexpr std::uint32_t kElemXtd = bit(30);
inline constexpr std::uint32_t kElemRtr = bit(29);
inline constexpr std::uint32_t kElemEsi = bit(31);
inline constexpr unsigned kElemStdIdShift = 18;
inline constexpr std::uint32_t kElemFdf = bit(21);
inline constexpr std::uint32_t kElemBrs = bit(20);
inline constexpr unsigned kElemDlcShift = 16;
}  // namespace fdcan

// --- USART, RM0433 §48.8 --------------------------------------------------------------------
namespace usart {
inline constexpr Addr kUsart1 = 0x40011000;
inline constexpr Addr kUsart2 = 0x40004400;
inline constexpr Addr kUsart3 = 0x40004800;
inline constexpr Addr kUsart6 = 0x40011400;
inline constexpr Addr kCr1 = 0x00;
inline constexpr std::uint32_t kCr1Ue = bit(0);
inline constexpr std::uint32_t kCr1Re = bit(2);
inline constexpr std::uint32_t kCr1Te = bit(3);
inline constexpr std::uint32_t kCr1Rxneie = bit(5);
inline constexpr std::uint32_t kCr1Tcie = bit(6);
inline constexpr std::uint32_t kCr1Ps = bit(9);
inline constexpr std::uint32_t kCr1Pce = bit(10);
inline constexpr std::uint32_t kCr1M0 = bit(12);
inline constexpr std::uint32_t kCr1Over8 = bit(15);
inline constexpr unsigned kCr1DedtShift = 16;  // DEDT[20:16], in 1/16 bit (OVER8 = 0)
inline constexpr unsigned kCr1DeatShift = 21;  // DEAT[25:21]
inline constexpr std::uint32_t kCr1Rtoie = bit(26);
inline constexpr Addr kCr2 = 0x04;
inline constexpr std::uint32_t kCr2Rtoen = bit(23);
inline constexpr Addr kCr3 = 0x08;
inline constexpr std::uint32_t kCr3Dem = bit(14);  // hardware driver-enable on RTS/DE pin
inline constexpr std::uint32_t kCr3Dep = bit(15);  // DE polarity: 0 = active high
inline constexpr Addr kBrr = 0x0C;
inline constexpr Addr kRtor = 0x14;   // RTO[23:0] in bit times
inline constexpr Addr kIsr = 0x1C;
inline constexpr std::uint32_t kIsrPe = bit(0);
inline constexpr std::uint32_t kIsrFe = bit(1);
inline constexpr std::uint32_t kIsrNe = bit(2);
inline constexpr std::uint32_t kIsrOre = bit(3);
inline constexpr std::uint32_t kIsrRxne = bit(5);
inline constexpr std::uint32_t kIsrTc = bit(6);
inline constexpr std::uint32_t kIsrTxe = bit(7);
inline constexpr std::uint32_t kIsrRtof = bit(11);
inline constexpr Addr kIcr = 0x20;
inline constexpr Addr kRdr = 0x24;
inline constexpr Addr kTdr = 0x28;
}  // namespace usart

// --- Independent watchdog, RM0433 §45.4 (IWDG1 base 0x5800 4800) ----------------------------
namespace iwdg {
inline constexpr Addr kIwdg1 = 0x58004800;
inline constexpr Addr kKr = 0x00;
inline constexpr Addr kPr = 0x04;   // PR[2:0]: divider 4 << PR
inline constexpr Addr kRlr = 0x08;  // RL[11:0]
inline constexpr Addr kSr = 0x0C;   // PVU 0, RVU 1, WVU 2
inline constexpr Addr kWinr = 0x10;
inline constexpr std::uint32_t kKeyStart = 0xCCCC;
inline constexpr std::uint32_t kKeyUnlock = 0x5555;
inline constexpr std::uint32_t kKeyReload = 0xAAAA;
}  // namespace iwdg

// --- Cortex-M7 system control space (ARMv7-M ARM §B3) --------------------------------------
namespace scb {
inline constexpr Addr kBase = 0xE000ED00;
inline constexpr Addr kVtor = 0x08;
inline constexpr Addr kAircr = 0x0C;   // VECTKEY 0x05FA << 16, PRIGROUP[10:8]
inline constexpr Addr kCcr = 0x14;     // DC bit 16, IC bit 17
inline constexpr std::uint32_t kCcrDc = bit(16);
inline constexpr std::uint32_t kCcrIc = bit(17);
inline constexpr Addr kShpr3 = 0x20;   // PendSV [23:16], SysTick [31:24]
inline constexpr Addr kCpacr = 0x88;   // CP10/CP11 full access = 0xF << 20
inline constexpr Addr kCcsidr = 0x80;  // (0xE000ED80 - base)
inline constexpr Addr kCsselr = 0x84;
// Cache maintenance operations (0xE000EF50..)
inline constexpr Addr kIciallu = 0xE000EF50;
inline constexpr Addr kDcisw = 0xE000EF60;
}  // namespace scb
namespace mpu {
inline constexpr Addr kBase = 0xE000ED90;
inline constexpr Addr kCtrl = 0x04;   // ENABLE 0, HFNMIENA 1, PRIVDEFENA 2
inline constexpr Addr kRnr = 0x08;
inline constexpr Addr kRbar = 0x0C;
inline constexpr Addr kRasr = 0x10;   // XN 28, AP[26:24], TEX[21:19], S 18, C 17, B 16, SRD[15:8], SIZE[5:1], ENABLE 0
}  // namespace mpu
namespace nvic {
inline constexpr Addr kIser = 0xE000E100;  // + 4 * (irq / 32)
inline constexpr Addr kIcer = 0xE000E180;
inline constexpr Addr kIpr = 0xE000E400;   // one byte per IRQ; M7 implements the top 4 bits
}  // namespace nvic
namespace systick {
inline constexpr Addr kCsr = 0xE000E010;  // ENABLE 0, TICKINT 1, CLKSOURCE 2 (1 = CPU clock)
inline constexpr Addr kRvr = 0xE000E014;
inline constexpr Addr kCvr = 0xE000E018;
}  // namespace systick
namespace dwt {
inline constexpr Addr kCtrl = 0xE0001000;    // CYCCNTENA bit 0
inline constexpr Addr kCyccnt = 0xE0001004;
inline constexpr Addr kLar = 0xE0001FB0;     // write 0xC5ACCE55 to unlock on the M7
inline constexpr Addr kDemcr = 0xE000EDFC;   // TRCENA bit 24
}  // namespace dwt

// --- STM32H743 interrupt numbers, RM0433 §19.1.2 table 145 -----------------------------------
namespace irq {
inline constexpr int kDma1Stream0 = 11;  // DMA1_Stream0..6 = 11..17, Stream7 = 47
inline constexpr int kExti9_5 = 23;
inline constexpr int kSpi1 = 35;
inline constexpr int kTim2 = 28;
inline constexpr int kTim3 = 29;
inline constexpr int kTim4 = 30;
inline constexpr int kUsart2 = 38;
inline constexpr int kUsart3 = 39;
inline constexpr int kExti15_10 = 40;
inline constexpr int kTim5 = 50;
inline constexpr int kFdcan1It0 = 19;
inline constexpr int kCount = 150;
}  // namespace irq

}  // namespace maglev::stm32h7
