!> The abstract time integrator: what the driver needs of every method. A method is started at
!> (t0, q, v) for a segment that ends at t_stop (a breakpoint or the last output time: it never
!> steps past it), advanced to target times (where it returns the state, stepped to or
!> interpolated), restarted after a breakpoint, and asked for its counters. The model is passed
!> to every call; a method that keeps its own reference to it (SUNDIALS) may ignore it.
!> integrators_driver's factory is the only place that knows the methods by name.
module integrators_base
  use core_kinds, only: wp
  use core_error, only: error_t
  use integrators_system, only: ode2_system_t, integrator_options_t, integrator_stats_t
  implicit none
  private
  public :: integrator_t

  type, abstract :: integrator_t
  contains
    procedure(start_iface), deferred :: start
    procedure(advance_iface), deferred :: advance
    procedure(restart_iface), deferred :: restart
    procedure(stats_iface), deferred :: get_stats
    !> Release what the method holds (SUNDIALS memory); safe to call more than once.
    procedure :: finish => integrator_finish
  end type integrator_t

  abstract interface
    subroutine start_iface(this, sys, opts, t0, q, v, t_stop, t_lo, t_hi, err)
      import :: integrator_t, ode2_system_t, integrator_options_t, error_t, wp
      class(integrator_t), intent(inout) :: this
      class(ode2_system_t), intent(inout), target :: sys
      type(integrator_options_t), intent(in) :: opts
      !> accel is only evaluated at times clamped into [t_lo, t_hi] (see the driver)
      real(wp), intent(in) :: t0, q(:), v(:), t_stop, t_lo, t_hi
      type(error_t), intent(inout) :: err
    end subroutine start_iface

    subroutine advance_iface(this, sys, t_target, q, v, err)
      import :: integrator_t, ode2_system_t, error_t, wp
      class(integrator_t), intent(inout) :: this
      class(ode2_system_t), intent(inout) :: sys
      real(wp), intent(in) :: t_target
      real(wp), intent(out) :: q(:), v(:)
      type(error_t), intent(inout) :: err
    end subroutine advance_iface

    subroutine restart_iface(this, sys, t, q, v, t_stop, t_lo, t_hi, err)
      import :: integrator_t, ode2_system_t, error_t, wp
      class(integrator_t), intent(inout) :: this
      class(ode2_system_t), intent(inout) :: sys
      real(wp), intent(in) :: t, q(:), v(:), t_stop, t_lo, t_hi
      type(error_t), intent(inout) :: err
    end subroutine restart_iface

    subroutine stats_iface(this, stats)
      import :: integrator_t, integrator_stats_t
      class(integrator_t), intent(in) :: this
      type(integrator_stats_t), intent(out) :: stats
    end subroutine stats_iface
  end interface

contains

  subroutine integrator_finish(this)
    class(integrator_t), intent(inout) :: this
  end subroutine integrator_finish
end module integrators_base
