package dev.trailprint

/**
 * How much memory the engine may use on this device: the `memoryBudgetMb` the app passes
 * in every plan, team plan and survey session (see [Trailprint.memoryBudgetMb]).
 *
 * The rule, from the device's total RAM: one eighth of it, at most 512 MiB and at least
 * 64 MiB; on a low-RAM device (Android's `ActivityManager.isLowRamDevice`) one sixteenth,
 * at least 64 MiB. Why: the engine refuses, before allocating, a request whose working set
 * would exceed the budget, so the budget must be what the phone can give one app without
 * the system killing it; an eighth of the RAM leaves room for the system, the app's own
 * heap and the other apps, and a low-RAM device has even less to spare. 512 MiB is the
 * engine's own default, which the desktop benchmarks meet, so a large phone gets exactly
 * that; 64 MiB is the floor below which even the demo-sized buildings would be refused
 * (and a refusal names the part of the building to plan instead). E.g. 2 GiB -> 256 MiB,
 * 3 GiB -> 384, 8 GiB -> 512, a 1 GiB low-RAM device -> 64.
 */
object DeviceMemory {
    /** The engine's default budget, MiB (what `null` means in the requests). */
    const val MAX_MB: Long = 512

    /** The least budget given, MiB. */
    const val MIN_MB: Long = 64

    /**
     * The memory budget, MiB, of a device with [totalRamBytes] of RAM
     * (`ActivityManager.MemoryInfo.totalMem`) and Android's [lowRam] flag.
     */
    fun budgetMb(totalRamBytes: Long, lowRam: Boolean): ULong {
        val totalMb = maxOf(totalRamBytes, 0L) / (1024L * 1024L)
        val share = if (lowRam) totalMb / 16 else totalMb / 8
        return share.coerceIn(MIN_MB, MAX_MB).toULong()
    }
}
