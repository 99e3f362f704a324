//! The `[vkf]` and `[nav_filter]` tables that the `ins-dvl` replay and the `vkf`
//! experiment both read: the keys of the velocity Kalman filter and of the 9-state
//! filter, listed once (their doc comments are the `vkf` experiment's rows of
//! `docs/scenarios.md`) in [`vkf_toml!`](crate::vkf_toml) and
//! [`nav_filter_toml!`](crate::nav_filter_toml), which declare each side's table with
//! its own keys added, and checked into the filters' configurations by the methods
//! the macros give the table.
//!
//! A macro and not one struct: the two tables differ by a few keys (the replay's
//! `vkf.rpm_sigma`, the experiment's rate and gate of `[nav_filter]`), and a shared
//! struct inside each table (`#[serde(flatten)]`) would cost the replay's file errors
//! their line, their key and the list of expected keys.

/// The types the tables' methods name, for the macros' expansions in other crates.
#[doc(hidden)]
pub mod __private {
    pub use fathom_estimators::integrated_nav::{
        AccelBiasFrame, IntegratedNavConfig, IntegratedNavParams,
    };
    pub use fathom_estimators::velocity_filter::{VelocityFilterConfig, VelocityFilterParams};
    pub use fathom_sim::SimError;
    pub use fathom_sim::parameter_key::parameter_invalid_aliased;
}

/// A settings table's struct with the derives and the strictness of every scenario
/// table (the two macros below fill in the keys).
#[doc(hidden)]
#[macro_export]
macro_rules! __filter_table {
    ($(#[$attr:meta])* $vis:vis struct $name:ident { $($body:tt)* }) => {
        $(#[$attr])*
        #[derive(Debug, Clone, PartialEq)]
        #[derive(::serde::Serialize, ::serde::Deserialize, ::schemars::JsonSchema)]
        #[serde(deny_unknown_fields)]
        $vis struct $name { $($body)* }
    };
}

/// Declares a `[vkf]` table: the velocity Kalman filter `[V, sf, b]`'s keys, then the
/// keys given after `..`, and its check
/// `velocity_filter_config(&self, file, speed0, rpm_sigma)`. The caller depends on
/// `serde` and `schemars`.
///
/// ```
/// fathom_replay::vkf_toml! {
///     /// `[vkf]` with one more key.
///     pub struct VkfTuningToml {
///         ..
///         /// Revolution noise σ.
///         pub rpm_sigma: f64,
///     }
/// }
/// ```
#[macro_export]
macro_rules! vkf_toml {
    (
        $(#[$attr:meta])*
        $vis:vis struct $name:ident {
            ..
            $($(#[$extra_attr:meta])* pub $extra:ident: $extra_ty:ty,)*
        }
    ) => {
        $crate::__filter_table! {
            $(#[$attr])*
            $vis struct $name {
                /// Initial scale-factor estimate (true value: `rpm.k_mps_per_rpm`).
                ///
                /// Unit: m/s per rpm. Range: finite.
                pub sf0: f64,
                /// Initial bias estimate (true value: `rpm.b_mps`).
                ///
                /// Unit: m/s. Range: finite.
                pub b0: f64,
                /// Initial forward-speed σ.
                ///
                /// Unit: m/s. Range: > 0.
                pub sigma_speed0_mps: f64,
                /// Initial scale-factor σ.
                ///
                /// Unit: m/s per rpm. Range: > 0.
                pub sigma_sf0: f64,
                /// Initial bias σ.
                ///
                /// Unit: m/s. Range: > 0.
                pub sigma_b0_mps: f64,
                /// Extra forward-speed process noise σ per VKF step (one step per DVL epoch).
                ///
                /// Unit: m/s. Range: ≥ 0.
                pub speed_process_sigma_mps: f64,
                /// Scale-factor random-walk PSD.
                ///
                /// Unit: (m/s/rpm)²/s. Range: ≥ 0.
                pub sf_rw_psd: f64,
                /// Bias random-walk PSD.
                ///
                /// Unit: (m/s)²/s. Range: ≥ 0.
                pub bias_rw_psd: f64,
                /// σ of the DVL forward body speed assumed by the VKF's update.
                ///
                /// Unit: m/s. Range: > 0.
                pub dvl_sigma_mps: f64,
                /// σ of the lateral and vertical body speeds assumed zero when the switching box
                /// uses RPM speed (eqs. 11-12).
                ///
                /// Unit: m/s. Range: > 0.
                pub lateral_sigma_mps: f64,
                $($(#[$extra_attr])* pub $extra: $extra_ty,)*
            }
        }

        impl $name {
            /// The VKF's configuration from these keys, the initial speed `speed0`
            /// (m/s) and the revolution noise `rpm_sigma` (rpm).
            ///
            /// # Errors
            /// `SimError::Invalid` naming the key of the value the filter refuses
            /// (the table `vkf` for the initial speed).
            pub fn velocity_filter_config(
                &self,
                file: &str,
                speed0: f64,
                rpm_sigma: f64,
            ) -> ::std::result::Result<
                $crate::ins_dvl::filter_tables::__private::VelocityFilterConfig,
                $crate::ins_dvl::filter_tables::__private::SimError,
            > {
                $crate::ins_dvl::filter_tables::__private::VelocityFilterParams {
                    speed0,
                    sf0: self.sf0,
                    b0: self.b0,
                    sigma0: [self.sigma_speed0_mps, self.sigma_sf0, self.sigma_b0_mps],
                    rpm_sigma,
                    speed_process_var: self.speed_process_sigma_mps * self.speed_process_sigma_mps,
                    sf_rw_psd: self.sf_rw_psd,
                    bias_rw_psd: self.bias_rw_psd,
                    dvl_sigma: self.dvl_sigma_mps,
                }
                .check()
                .map_err(|e| {
                    $crate::ins_dvl::filter_tables::__private::parameter_invalid_aliased(
                        file,
                        "vkf",
                        self,
                        &e,
                        &[
                            ("sigma0[0]", "sigma_speed0_mps"),
                            ("sigma0[1]", "sigma_sf0"),
                            ("sigma0[2]", "sigma_b0_mps"),
                        ],
                    )
                })
            }
        }
    };
}

/// Declares a `[nav_filter]` table: the keys given before `..`, the 9-state `[p, v,
/// accel bias]` filter's keys, then the keys given after `..`; and its check
/// `integrated_nav_config(&self, file)`. The caller depends on `serde` and
/// `schemars`.
///
/// ```
/// fathom_replay::nav_filter_toml! {
///     /// `[nav_filter]` with a key before the filter's.
///     pub struct NavTuningToml {
///         /// Covariance period, s.
///         pub covariance_period_s: f64,
///         ..
///     }
/// }
/// ```
#[macro_export]
macro_rules! nav_filter_toml {
    (
        $(#[$attr:meta])*
        $vis:vis struct $name:ident {
            $($(#[$first_attr:meta])* pub $first:ident: $first_ty:ty,)*
            ..
            $($(#[$extra_attr:meta])* pub $extra:ident: $extra_ty:ty,)*
        }
    ) => {
        $crate::__filter_table! {
            $(#[$attr])*
            $vis struct $name {
                $($(#[$first_attr])* pub $first: $first_ty,)*
                /// White acceleration PSD of the 9-state filter.
                ///
                /// Unit: m²/s³. Range: > 0.
                pub accel_psd: f64,
                /// Acceleration-bias random-walk PSD of the 9-state filter.
                ///
                /// Unit: (m/s²)²/s. Range: ≥ 0.
                pub accel_bias_rw_psd: f64,
                /// Initial position σ of the 9-state filters and the ESKF.
                ///
                /// Unit: m. Range: > 0.
                pub sigma0_pos_m: f64,
                /// Initial velocity σ of the 9-state filters and the ESKF.
                ///
                /// Unit: m/s. Range: > 0.
                pub sigma0_vel_mps: f64,
                /// Initial acceleration-bias σ of the 9-state filter.
                ///
                /// Unit: m/s². Range: > 0.
                pub sigma0_accel_bias_mps2: f64,
                /// Frame of the 9-state filter's bias: `"body"` an accelerometer bias (enters as
                /// `C_b^n b`), `"nav"` a bias of the navigation-frame acceleration input (dominated
                /// by the uncorrected INS tilt).
                ///
                /// Range: `"body"` or `"nav"`.
                pub accel_bias_frame: String,
                $($(#[$extra_attr])* pub $extra: $extra_ty,)*
            }
        }

        impl $name {
            /// The 9-state filter's configuration from these keys.
            ///
            /// # Errors
            /// `SimError::Invalid` naming `nav_filter.accel_bias_frame` for another
            /// spelling, or the key of the value the filter refuses.
            pub fn integrated_nav_config(
                &self,
                file: &str,
            ) -> ::std::result::Result<
                $crate::ins_dvl::filter_tables::__private::IntegratedNavConfig,
                $crate::ins_dvl::filter_tables::__private::SimError,
            > {
                use $crate::ins_dvl::filter_tables::__private::{
                    AccelBiasFrame, IntegratedNavParams, SimError,
                };
                IntegratedNavParams {
                    accel_psd: self.accel_psd,
                    accel_bias_rw_psd: self.accel_bias_rw_psd,
                    sigma0: [
                        self.sigma0_pos_m,
                        self.sigma0_vel_mps,
                        self.sigma0_accel_bias_mps2,
                    ],
                    bias_frame: match self.accel_bias_frame.as_str() {
                        "body" => AccelBiasFrame::Body,
                        "nav" => AccelBiasFrame::Nav,
                        other => {
                            return Err(SimError::invalid(
                                file,
                                "nav_filter.accel_bias_frame",
                                format!("must be \"body\" or \"nav\", got {other:?}"),
                            ));
                        }
                    },
                }
                .check()
                .map_err(|e| {
                    $crate::ins_dvl::filter_tables::__private::parameter_invalid_aliased(
                        file,
                        "nav_filter",
                        self,
                        &e,
                        &[
                            ("sigma0[0]", "sigma0_pos_m"),
                            ("sigma0[1]", "sigma0_vel_mps"),
                            ("sigma0[2]", "sigma0_accel_bias_mps2"),
                        ],
                    )
                })
            }
        }
    };
}
