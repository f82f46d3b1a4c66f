// The Compose app. Everything that is not UI or Android sensor glue lives in :core-jvm.
plugins {
    id("com.android.application")
    id("org.jetbrains.kotlin.android")
    id("org.jetbrains.kotlin.plugin.compose")
}

val cargoWorkspace = rootProject.extra["cargoWorkspace"] as File
val jniLibsDir = file("src/main/jniLibs")

// libtrailprint_ffi.so for the two ABIs phones and emulators use, with cargo-ndk
// (`cargo install cargo-ndk`; `rustup target add aarch64-linux-android x86_64-linux-android`;
// the NDK from Android Studio's SDK manager, or ANDROID_NDK_HOME).
val cargoNdk by tasks.registering(Exec::class) {
    group = "rust"
    description = "cargo ndk -t arm64-v8a -t x86_64 build --release -p trailprint-bindings"
    workingDir = cargoWorkspace
    commandLine(
        "cargo", "ndk", "-t", "arm64-v8a", "-t", "x86_64", "-o", jniLibsDir.path,
        "build", "--release", "-p", "trailprint-bindings",
    )
}

android {
    namespace = "dev.trailprint.app"
    compileSdk = 35

    defaultConfig {
        applicationId = "dev.trailprint.app"
        minSdk = 26
        targetSdk = 35
        versionCode = 1
        versionName = "0.1.0"
        ndk { abiFilters += listOf("arm64-v8a", "x86_64") }
    }

    buildTypes {
        release {
            isMinifyEnabled = false
        }
    }
    compileOptions {
        sourceCompatibility = JavaVersion.VERSION_17
        targetCompatibility = JavaVersion.VERSION_17
    }
    kotlinOptions { jvmTarget = "17" }
    buildFeatures { compose = true }
    // The demo building ships as an asset.
    sourceSets["main"].assets.srcDir("../demo")
}

tasks.named("preBuild") { dependsOn(cargoNdk) }

dependencies {
    implementation(project(":core-jvm"))
    implementation("net.java.dev.jna:jna:5.13.0@aar")
    implementation("org.jetbrains.kotlinx:kotlinx-coroutines-android:1.9.0")

    val composeBom = platform("androidx.compose:compose-bom:2024.12.01")
    implementation(composeBom)
    implementation("androidx.compose.ui:ui")
    implementation("androidx.compose.foundation:foundation")
    implementation("androidx.compose.material3:material3")
    implementation("androidx.core:core-ktx:1.13.1") // FileProvider, ServiceCompat, NotificationCompat
    implementation("androidx.activity:activity-compose:1.9.3")
    implementation("androidx.lifecycle:lifecycle-viewmodel-compose:2.8.7")
    implementation("androidx.lifecycle:lifecycle-runtime-compose:2.8.7")
    implementation("com.squareup.okhttp3:okhttp:4.12.0")
}
