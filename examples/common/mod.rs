//! Firmware support shared by the examples: defmt over semihosting, and a run that always ends.
//!
//! A panic or a HardFault logs what happened and leaves QEMU with exit status 1 instead of
//! hanging, so a failing example fails the command that ran it.

use cortex_m_rt::{ExceptionFrame, exception};
use cortex_m_semihosting::debug;
use defmt_semihosting as _;

/// Ends the run: QEMU exits with status 0 on success and 1 otherwise.
pub fn exit(success: bool) -> ! {
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    // Only reached without a semihosting host (a board without a debugger): stop here.
    loop {
        cortex_m::asm::bkpt();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic: {}", defmt::Display2Format(info));
    exit(false)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    defmt::error!("HardFault at pc = {=u32:#010x}", frame.pc());
    exit(false)
}
