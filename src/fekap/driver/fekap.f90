!> What the program needs of FEKAP, in one module: read a deck, settle the
!> model (or turn a planar one into its spatial model), make its stepper, open the output files and run the time loop;
!> errors as values, and the signals and pipes of the process.
module fekap
   use fekap_error, only: error_type, fatal_error, error_other, error_input, error_analysis, error_output
   use fekap_model, only: model_type
   use fekap_deck, only: read_deck
   use fekap_stepping_stepper, only: stepper_type
   use fekap_stepping_interrupt, only: catch_interrupts, interrupt_signal, interrupt_reads
   use fekap_posix, only: os_ignore_write_signals
   use fekap_output_writer, only: writer_list_type
   use fekap_output_listing, only: plan_text
   use fekap_driver_factory, only: settle_model, make_stepper
   use fekap_spatial_from_planar, only: spatial_from_planar
   use fekap_driver_outputs, only: open_outputs
   use fekap_driver_run, only: run_analysis, step_count
   implicit none
   private

   public :: error_type, fatal_error, error_other, error_input, error_analysis, error_output
   public :: model_type, read_deck
   public :: stepper_type, settle_model, make_stepper, spatial_from_planar
   public :: writer_list_type, open_outputs, run_analysis, step_count, plan_text
   public :: catch_interrupts, interrupt_signal, interrupt_reads, os_ignore_write_signals

end module fekap
