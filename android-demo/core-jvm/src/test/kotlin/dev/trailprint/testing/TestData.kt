package dev.trailprint.testing

import java.io.File

/** Files the tests share; the repository root comes from `-Dtrailprint.repo`. */
object TestData {
    val repo: File = File(System.getProperty("trailprint.repo") ?: ".").absoluteFile

    val demoBuildingFile: File = File(repo, "android-demo/demo/demo-building.json")

    val demoBuildingJson: String by lazy { demoBuildingFile.readText() }
}
