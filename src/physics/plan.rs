//! The plan of a calculation: each stage it ran or skipped, and why (api.md `plan`).

/// One stage of a calculation's plan.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Stage {
    /// Stage name, e.g. `impact`, `curve`, `migration`, `release`, `checks`.
    pub stage: &'static str,
    /// Ran (true) or skipped.
    pub ran: bool,
    /// Why it ran or was skipped.
    pub reason: String,
}

impl Stage {
    /// A stage that ran, and how.
    pub fn ran(stage: &'static str, reason: impl Into<String>) -> Self {
        Self {
            stage,
            ran: true,
            reason: reason.into(),
        }
    }

    /// A stage that was skipped, and why.
    pub fn skipped(stage: &'static str, reason: impl Into<String>) -> Self {
        Self {
            stage,
            ran: false,
            reason: reason.into(),
        }
    }
}
