//! placeholder
pub struct ConditionReport;
